// SPDX-License-Identifier: AGPL-3.0-or-later
// Reading a tiled model (spec/tiles.md): its index, decoding tiles and
// merging them by the border rule; `hmc dec TILED` and `hmc info TILED`.
#include "tiles.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include "hmc/meshio.hpp"

namespace fs = std::filesystem;

namespace hmc::cli {

namespace {

// --- A small JSON reader: enough for tiles.json (RFC 8259 values). ---------
struct JValue {
  enum Type { null, boolean, number, string, array, object } type = null;
  bool b = false;
  std::string text;  // number: its literal; string: its value
  std::vector<JValue> items;
  std::vector<std::pair<std::string, JValue>> members;
  const JValue* get(const std::string& k) const {
    for (const auto& [key, v] : members)
      if (key == k) return &v;
    return nullptr;
  }
};

class JParser {
 public:
  explicit JParser(const std::string& s) : s_(s) {}
  bool parse(JValue& v, std::string& err) {
    if (!value(v, 0)) {
      err = err_ + " at byte " + std::to_string(at_);
      return false;
    }
    ws();
    if (at_ != s_.size()) {
      err = "trailing characters at byte " + std::to_string(at_);
      return false;
    }
    return true;
  }

 private:
  void ws() {
    while (at_ < s_.size() && (s_[at_] == ' ' || s_[at_] == '\n' || s_[at_] == '\r' || s_[at_] == '\t')) ++at_;
  }
  bool fail(const char* why) {
    err_ = why;
    return false;
  }
  bool lit(const char* w) {
    const std::size_t n = std::strlen(w);
    if (s_.compare(at_, n, w) != 0) return fail("bad literal");
    at_ += n;
    return true;
  }
  bool str(std::string& out) {
    ++at_;  // the opening quote
    while (at_ < s_.size() && s_[at_] != '"') {
      char c = s_[at_++];
      if (static_cast<unsigned char>(c) < 0x20) return fail("control character in a string");
      if (c == '\\') {
        if (at_ >= s_.size()) return fail("unterminated string");
        c = s_[at_++];
        switch (c) {
          case '"': case '\\': case '/': out += c; break;
          case 'b': out += '\b'; break;
          case 'f': out += '\f'; break;
          case 'n': out += '\n'; break;
          case 'r': out += '\r'; break;
          case 't': out += '\t'; break;
          case 'u': {  // kept only for ASCII; tiles.json needs no more
            if (at_ + 4 > s_.size()) return fail("bad \\u escape");
            const unsigned long cp = std::strtoul(s_.substr(at_, 4).c_str(), nullptr, 16);
            at_ += 4;
            out += cp < 0x80 ? static_cast<char>(cp) : '?';
            break;
          }
          default: return fail("bad escape");
        }
      } else {
        out += c;
      }
    }
    if (at_ >= s_.size()) return fail("unterminated string");
    ++at_;
    return true;
  }
  bool value(JValue& v, int depth) {
    if (depth > 64) return fail("nested too deeply");
    ws();
    if (at_ >= s_.size()) return fail("unexpected end");
    const char c = s_[at_];
    if (c == '{') {
      v.type = JValue::object;
      ++at_;
      ws();
      if (at_ < s_.size() && s_[at_] == '}') return ++at_, true;
      for (;;) {
        ws();
        if (at_ >= s_.size() || s_[at_] != '"') return fail("expected a member name");
        std::string k;
        if (!str(k)) return false;
        ws();
        if (at_ >= s_.size() || s_[at_] != ':') return fail("expected ':'");
        ++at_;
        JValue m;
        if (!value(m, depth + 1)) return false;
        v.members.emplace_back(std::move(k), std::move(m));
        ws();
        if (at_ < s_.size() && s_[at_] == ',') { ++at_; continue; }
        if (at_ < s_.size() && s_[at_] == '}') return ++at_, true;
        return fail("expected ',' or '}'");
      }
    }
    if (c == '[') {
      v.type = JValue::array;
      ++at_;
      ws();
      if (at_ < s_.size() && s_[at_] == ']') return ++at_, true;
      for (;;) {
        JValue m;
        if (!value(m, depth + 1)) return false;
        v.items.push_back(std::move(m));
        ws();
        if (at_ < s_.size() && s_[at_] == ',') { ++at_; continue; }
        if (at_ < s_.size() && s_[at_] == ']') return ++at_, true;
        return fail("expected ',' or ']'");
      }
    }
    if (c == '"') {
      v.type = JValue::string;
      return str(v.text);
    }
    if (c == 't') return v.type = JValue::boolean, v.b = true, lit("true");
    if (c == 'f') return v.type = JValue::boolean, lit("false");
    if (c == 'n') return lit("null");
    const std::size_t start = at_;
    while (at_ < s_.size() && std::strchr("+-0123456789.eE", s_[at_])) ++at_;
    if (at_ == start) return fail("unexpected character");
    v.type = JValue::number;
    v.text = s_.substr(start, at_ - start);
    return true;
  }
  const std::string& s_;
  std::size_t at_ = 0;
  std::string err_;
};

bool as_u64(const JValue* v, std::uint64_t& out) {
  if (!v || v->type != JValue::number || v->text.empty() || v->text[0] == '-') return false;
  char* end = nullptr;
  errno = 0;
  out = std::strtoull(v->text.c_str(), &end, 10);
  return *end == 0 && errno == 0;
}
bool as_double(const JValue* v, double& out) {
  if (!v || v->type != JValue::number) return false;
  char* end = nullptr;
  out = std::strtod(v->text.c_str(), &end);
  return *end == 0 && std::isfinite(out);
}
bool as_u64s(const JValue* v, std::vector<std::uint64_t>& out) {
  if (!v || v->type != JValue::array) return false;
  out.clear();
  for (const auto& i : v->items) {
    std::uint64_t u;
    if (!as_u64(&i, u)) return false;
    out.push_back(u);
  }
  return true;
}

std::uint32_t crc32(const std::string& bytes) {
  static std::uint32_t table[256];
  static bool ready = false;
  if (!ready) {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      table[i] = c;
    }
    ready = true;
  }
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : bytes) c = table[(c ^ b) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

Error bad(const std::string& where, const std::string& what) { return Error{Status::bad_header, where + ": " + what}; }

bool owns(const TileEntry& t, const GridPoint& p) {
  for (int a = 0; a < 3; ++a)
    if (static_cast<std::int64_t>(p[a]) < t.box[a] || static_cast<std::int64_t>(p[a]) >= t.box[3 + a]) return false;
  return true;
}

}  // namespace

bool is_tiled(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec) ? fs::is_regular_file(fs::path(path) / "tiles.json", ec)
                                    : fs::path(path).filename() == "tiles.json";
}

Result<TileIndex> load_index(const std::string& path) {
  std::error_code ec;
  const fs::path file = fs::is_directory(path, ec) ? fs::path(path) / "tiles.json" : fs::path(path);
  const std::string where = file.string();
  auto text = io::read_file(where, 1ull << 30);
  if (!text) return text.error();
  JValue root;
  std::string err;
  if (!JParser(text.value()).parse(root, err)) return bad(where, "not JSON: " + err);
  if (root.type != JValue::object) return bad(where, "not a JSON object");
  TileIndex ix;
  ix.dir = file.parent_path().string();
  const JValue* f = root.get("format");
  if (!f || f->type != JValue::string || f->text != "hmc-tiles") return bad(where, "format is not \"hmc-tiles\"");
  const JValue* ver = root.get("version");
  if (!ver || ver->type != JValue::string || ver->text.substr(0, ver->text.find('.')) != "0")
    return Error{Status::unsupported_version, where + ": unsupported tiles.json version"};
  const JValue* kind = root.get("kind");
  if (!kind || kind->type != JValue::string) return bad(where, "no kind");
  if (kind->text == "points") ix.kind = Kind::points;
  else if (kind->text == "surface") ix.kind = Kind::surface;
  else if (kind->text == "volume") ix.kind = Kind::volume;
  else return bad(where, "unknown kind '" + kind->text + "'");
  std::uint64_t u = 0;
  if (!as_u64(root.get("q"), u) || u < 1 || u > 21) return bad(where, "q must be 1 to 21");
  ix.quantizer.bits = static_cast<int>(u);
  const JValue* origin = root.get("origin");
  if (!origin || origin->type != JValue::array || origin->items.size() != 3) return bad(where, "origin must be 3 numbers");
  for (int a = 0; a < 3; ++a)
    if (!as_double(&origin->items[a], ix.quantizer.origin[a])) return bad(where, "origin must be 3 finite numbers");
  if (!as_double(root.get("step"), ix.quantizer.step) || !(ix.quantizer.step > 0)) return bad(where, "step must be > 0");
  std::uint64_t margin = 0, levels = 0;
  if (!as_u64(root.get("margin"), margin)) return bad(where, "no margin");
  if (!as_u64(root.get("levels"), levels) || levels < 1 || levels > 64) return bad(where, "levels must be 1 to 64");
  if (!as_u64(root.get("points"), ix.points)) return bad(where, "no points");
  ix.margin = static_cast<std::int64_t>(margin);
  ix.levels = static_cast<int>(levels);
  const JValue* tiles = root.get("tiles");
  if (!tiles || tiles->type != JValue::array || tiles->items.empty()) return bad(where, "no tiles");
  const auto cells = static_cast<std::int64_t>(ix.quantizer.cells());
  std::uint64_t volume = 0, points = 0;
  for (std::size_t i = 0; i < tiles->items.size(); ++i) {
    const JValue& t = tiles->items[i];
    const std::string tw = where + ": tile " + std::to_string(i);
    TileEntry e;
    const JValue* name = t.get("file");
    if (!name || name->type != JValue::string || name->text.empty() || name->text == "." || name->text == ".." ||
        name->text.find('/') != std::string::npos || name->text.find('\\') != std::string::npos)
      return bad(tw, "file must be a plain file name");
    e.file = name->text;
    std::vector<std::uint64_t> box, bounds;
    if (!as_u64s(t.get("box"), box) || box.size() != 6 || !as_u64s(t.get("bounds"), bounds) || bounds.size() != 6)
      return bad(tw, "box and bounds must be 6 integers each");
    std::uint64_t vol = 1;
    for (int a = 0; a < 3; ++a) {
      e.box[a] = static_cast<std::int64_t>(box[a]);
      e.box[3 + a] = static_cast<std::int64_t>(box[3 + a]);
      e.bounds[a] = static_cast<std::int64_t>(bounds[a]);
      e.bounds[3 + a] = static_cast<std::int64_t>(bounds[3 + a]);
      if (!(box[a] < box[3 + a] && box[3 + a] <= static_cast<std::uint64_t>(cells))) return bad(tw, "box outside the lattice or empty");
      if (!(box[a] <= bounds[a] && bounds[a] <= bounds[3 + a] && bounds[3 + a] < box[3 + a]))
        return bad(tw, "bounds not inside the box");
      vol *= box[3 + a] - box[a];
    }
    volume += vol;
    std::uint64_t tl = 0;
    if (!as_u64(t.get("points"), e.points) || e.points < 1) return bad(tw, "points must be >= 1");
    if (!as_u64(t.get("levels"), tl) || tl < levels || tl > 64) return bad(tw, "levels must be the model's or more, at most 64");
    e.levels = static_cast<int>(tl);
    if (!as_u64s(t.get("stream_points"), e.stream_points) || e.stream_points.size() != tl ||
        !as_u64s(t.get("level_bytes"), e.level_bytes) || e.level_bytes.size() != tl)
      return bad(tw, "stream_points and level_bytes must have one entry per level");
    if (!as_u64(t.get("bytes"), e.bytes)) return bad(tw, "no bytes");
    for (auto b : e.level_bytes)
      if (b > e.bytes) return bad(tw, "a level's prefix is longer than the file");
    const JValue* crc = t.get("crc32");
    char* end = nullptr;
    if (!crc || crc->type != JValue::string || crc->text.size() != 8) return bad(tw, "crc32 must be 8 hex digits");
    e.crc32 = static_cast<std::uint32_t>(std::strtoul(crc->text.c_str(), &end, 16));
    if (*end) return bad(tw, "crc32 must be 8 hex digits");
    points += e.points;
    ix.tiles.push_back(std::move(e));
  }
  // The boxes partition the lattice: pairwise disjoint, volumes summing to it.
  for (std::size_t i = 0; i < ix.tiles.size(); ++i)
    for (std::size_t j = i + 1; j < ix.tiles.size(); ++j) {
      const auto &bu = ix.tiles[i].box, &bv = ix.tiles[j].box;
      bool meet = true;
      for (int a = 0; a < 3; ++a) meet = meet && bu[a] < bv[3 + a] && bv[a] < bu[3 + a];
      if (meet) return bad(where, "the boxes of tiles " + std::to_string(i) + " and " + std::to_string(j) + " overlap");
    }
  const std::uint64_t all = std::uint64_t{1} << (3 * ix.quantizer.bits);
  if (volume != all) return bad(where, "the tiles' boxes do not cover the lattice");
  if (points != ix.points) return bad(where, "points is not the sum of the tiles' points");
  return ix;
}

Result<Merged> decode_tiles(const TileIndex& ix, const std::vector<std::size_t>& which, int level, bool all_levels,
                            const DecodeOptions& base) {
  if (level < 0 || level >= ix.levels)
    return Error{Status::invalid_argument, "level " + std::to_string(level) + " is not in the model (levels 0 to " +
                                               std::to_string(ix.levels - 1) + ")"};
  Merged m;
  const int coarsest = all_levels ? ix.levels - 1 : level;
  const auto n_levels = static_cast<std::size_t>(coarsest - level + 1);
  m.levels.resize(n_levels);
  for (std::size_t k = 0; k < n_levels; ++k) m.levels[k].lod = coarsest - static_cast<int>(k);
  // Kept simplices by their corners' lattice points, before renumbering.
  std::vector<std::vector<std::array<GridPoint, 3>>> tris(n_levels);
  std::vector<std::vector<std::array<GridPoint, 4>>> tets(n_levels);
  for (std::size_t w : which) {
    const TileEntry& t = ix.tiles[w];
    const std::string path = (fs::path(ix.dir) / t.file).string();
    // Level 0 reads the whole file and checks it; a coarser level reads
    // only its prefix (what a client fetches with a range request).
    const bool whole = level == 0;
    const std::uint64_t want = whole ? t.bytes : t.level_bytes[static_cast<std::size_t>(level)];
    std::string bytes;
    {
      std::ifstream f(path, std::ios::binary);
      if (!f) return Error{Status::io_error, "cannot open " + path};
      bytes.resize(want);
      f.read(bytes.data(), static_cast<std::streamsize>(want));
      if (static_cast<std::uint64_t>(f.gcount()) != want) return Error{Status::truncated, path + ": shorter than the index says"};
      if (whole && f.peek() != std::char_traits<char>::eof()) return Error{Status::bad_header, path + ": longer than the index says"};
    }
    if (whole && crc32(bytes) != t.crc32) return Error{Status::crc_mismatch, path + ": CRC-32 differs from the index's"};
    m.bytes_read += want;
    DecodeOptions opt = base;
    opt.finest_level = level;
    opt.rebuild_coarser_levels = all_levels && base.reconstruct;
    auto dec = decode(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), opt);
    if (!dec) return Error{dec.error().status, path + ": " + dec.error().message};
    const Decoded& d = dec.value();
    if (d.kind != ix.kind) return bad(path, "kind differs from the index's");
    if (d.quantizer.bits != ix.quantizer.bits || d.quantizer.origin != ix.quantizer.origin || d.quantizer.step != ix.quantizer.step)
      return bad(path, "lattice (SQNT) differs from the index's");
    for (std::size_t k = 0; k < n_levels; ++k) {
      const int lod = m.levels[k].lod;
      const DecodedLevel* dl = nullptr;
      for (const auto& l : d.levels)
        if (l.lod == lod) dl = &l;
      if (!dl) return Error{Status::truncated, path + ": level " + std::to_string(lod) + " missing"};
      std::uint64_t owned = 0;
      for (const auto& p : dl->points)
        if (owns(t, p)) m.levels[k].points.push_back(p), ++owned;
      if (lod == 0 && owned != t.points)
        return bad(path, "owns " + std::to_string(owned) + " points, the index says " + std::to_string(t.points));
      // The border rule: keep a simplex whose first corner in canonical
      // order (its smallest index) this tile owns.
      for (const auto& s : dl->triangles)
        if (owns(t, dl->points[*std::min_element(s.begin(), s.end())]))
          tris[k].push_back({dl->points[s[0]], dl->points[s[1]], dl->points[s[2]]});
      for (const auto& s : dl->tetrahedra)
        if (owns(t, dl->points[*std::min_element(s.begin(), s.end())]))
          tets[k].push_back({dl->points[s[0]], dl->points[s[1]], dl->points[s[2]], dl->points[s[3]]});
      m.levels[k].rebuilt = dl->rebuilt;
    }
    ++m.tiles_read;
  }
  for (std::size_t k = 0; k < n_levels; ++k) {
    auto& pts = m.levels[k].points;
    const std::size_t owned = pts.size();
    for (const auto& s : tris[k]) pts.insert(pts.end(), s.begin(), s.end());
    for (const auto& s : tets[k]) pts.insert(pts.end(), s.begin(), s.end());
    std::sort(pts.begin(), pts.end());
    pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
    m.levels[k].foreign_points = pts.size() - std::min(pts.size(), owned);
    auto index_of = [&](const GridPoint& p) {
      return static_cast<std::uint32_t>(std::lower_bound(pts.begin(), pts.end(), p) - pts.begin());
    };
    for (const auto& s : tris[k]) m.levels[k].triangles.push_back({index_of(s[0]), index_of(s[1]), index_of(s[2])});
    for (const auto& s : tets[k])
      m.levels[k].tetrahedra.push_back({index_of(s[0]), index_of(s[1]), index_of(s[2]), index_of(s[3])});
  }
  return m;
}

std::vector<std::size_t> tiles_in_region(const TileIndex& ix, const std::array<double, 6>& r) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < ix.tiles.size(); ++i) {
    const auto& b = ix.tiles[i].bounds;
    bool meet = true;
    for (int a = 0; a < 3; ++a) {
      const double lo = ix.quantizer.origin[a] + static_cast<double>(b[a]) * ix.quantizer.step;
      const double hi = ix.quantizer.origin[a] + static_cast<double>(b[3 + a]) * ix.quantizer.step;
      meet = meet && lo <= r[3 + a] && r[a] <= hi;
    }
    if (meet) out.push_back(i);
  }
  return out;
}

int dec_tiled(Args& a, DecodeOptions opt) {
  const std::string in = a.positional()[0];
  auto ix = load_index(in);
  if (!ix) return report(in, ix.error(), Stage::input);
  const TileIndex& index = ix.value();
  std::vector<std::size_t> which(index.tiles.size());
  for (std::size_t i = 0; i < which.size(); ++i) which[i] = i;
  if (a.has("--region")) {
    const auto v = parse_doubles(a.get("--region"));
    if (v.size() != 6 || v[0] > v[3] || v[1] > v[4] || v[2] > v[5]) {
      std::fprintf(stderr, "hmc dec: --region takes xmin,ymin,zmin,xmax,ymax,zmax (min <= max)\n");
      return kUsage;
    }
    which = tiles_in_region(index, {v[0], v[1], v[2], v[3], v[4], v[5]});
  }
  if (a.has("--all-levels")) {
    std::fprintf(stderr, "hmc dec: --all-levels is not available for a tiled model (use --canonical or --level)\n");
    return kUsage;
  }
  const std::string out = a.has("-o") ? a.get("-o") : a.get("--output");
  const bool canonical = a.has("--canonical");
  const auto t0 = std::chrono::steady_clock::now();
  auto merged = decode_tiles(index, which, opt.finest_level, canonical, opt);
  if (!merged) return report(in, merged.error(), Stage::input);
  const auto t1 = std::chrono::steady_clock::now();
  const Merged& m = merged.value();
  std::uint64_t total_bytes = 0;
  for (const auto& t : index.tiles) total_bytes += t.bytes;
  std::fprintf(stderr, "hmc dec: %s: %zu of %zu tiles, %llu of %llu bytes read, %.3f s\n", in.c_str(), m.tiles_read,
               index.tiles.size(), static_cast<unsigned long long>(m.bytes_read),
               static_cast<unsigned long long>(total_bytes), std::chrono::duration<double>(t1 - t0).count());
  Outputs written;
  const MergedLevel& fin = m.levels.back();
  if (!out.empty()) {
    Mesh mesh;
    for (const auto& p : fin.points) mesh.points.push_back(index.quantizer.dequantize(p));
    mesh.triangles = fin.triangles;
    mesh.tetrahedra = fin.tetrahedra;
    io::WriteOptions wo;
    wo.float32 = a.get("--coords", "auto") == "float";
    auto w = io::write_mesh(out, mesh, io::Format::automatic, wo);
    if (!w) return report("cannot write " + out, w.error(), Stage::output);
    written.add(out);
  }
  if (canonical) {
    const std::string dir = a.get("--canonical");
    const bool existed = exists(dir);
    std::vector<std::uint64_t> declared;
    std::vector<DumpLevel> levels;
    for (const auto& l : m.levels) {
      declared.push_back(l.points.size());
      levels.push_back({l.lod, &l.points, &l.triangles, &l.tetrahedra, !opt.reconstruct});
    }
    // header.json lists the model's levels; those finer than the one decoded
    // down to are not in this dump.
    auto w = write_canonical_dump(dir, index.kind, index.quantizer, declared, levels);
    if (!w) return report("cannot write the canonical dump", w.error(), Stage::output);
    if (!existed) written.add(dir);
  }
  written.commit();
  const double secs = std::chrono::duration<double>(t1 - t0).count();
  if (a.flag("--json")) {
    Json j;
    j.begin_object();
    j.key("input").value(in).key("kind").value(kind_name(index.kind)).key("q").value(index.quantizer.bits);
    j.key("tiles").value(static_cast<std::uint64_t>(index.tiles.size()));
    j.key("tiles_read").value(static_cast<std::uint64_t>(m.tiles_read));
    j.key("bytes_read").value(m.bytes_read).key("bytes_total").value(total_bytes);
    j.key("decode_seconds").value(secs);
    j.key("levels").begin_array();
    for (const auto& l : m.levels) {
      j.begin_object();
      j.key("level").value(l.lod).key("points").value(static_cast<std::uint64_t>(l.points.size()));
      j.key("foreign_points").value(static_cast<std::uint64_t>(l.foreign_points));
      j.key("triangles").value(static_cast<std::uint64_t>(l.triangles.size()));
      j.key("tetrahedra").value(static_cast<std::uint64_t>(l.tetrahedra.size()));
      j.end_object();
    }
    j.end_array().end_object();
    std::fputs(j.str().c_str(), stdout);
  } else {
    std::printf("%s: tiled %s, q = %d, %zu of %zu tiles decoded in %.3f s\n", in.c_str(), kind_name(index.kind),
                index.quantizer.bits, m.tiles_read, index.tiles.size(), secs);
    std::printf("%6s %10s %10s %10s\n", "level", "points", "triangles", "tetrahedra");
    for (const auto& l : m.levels)
      std::printf("%6d %10zu %10zu %10zu\n", l.lod, l.points.size(), l.triangles.size(), l.tetrahedra.size());
  }
  return kOk;
}

int info_tiled(const std::string& in, bool json) {
  auto ix = load_index(in);
  if (!ix) return report(in, ix.error(), Stage::input);
  const TileIndex& index = ix.value();
  std::uint64_t bytes = 0, stream_points = 0;
  std::vector<std::uint64_t> level_bytes(static_cast<std::size_t>(index.levels), 0);
  for (const auto& t : index.tiles) {
    bytes += t.bytes;
    stream_points += t.stream_points[0];
    for (std::size_t k = 0; k < level_bytes.size(); ++k) level_bytes[k] += t.level_bytes[k];
  }
  const auto& q = index.quantizer;
  if (json) {
    Json j;
    j.begin_object();
    j.key("input").value(in).key("kind").value(kind_name(index.kind)).key("q").value(q.bits);
    j.key("origin").begin_array().value(q.origin[0]).value(q.origin[1]).value(q.origin[2]).end_array();
    j.key("step").value(q.step).key("margin").value(static_cast<std::int64_t>(index.margin));
    j.key("levels").value(index.levels).key("points").value(index.points);
    j.key("stream_points").value(stream_points).key("bytes").value(bytes);
    j.key("bits_per_point").value(8.0 * static_cast<double>(bytes) / static_cast<double>(index.points));
    j.key("level_bytes").begin_array();
    for (auto b : level_bytes) j.value(b);
    j.end_array();
    j.key("tiles").begin_array();
    for (const auto& t : index.tiles) {
      j.begin_object().key("file").value(t.file).key("points").value(t.points);
      j.key("stream_points").value(t.stream_points[0]).key("levels").value(t.levels).key("bytes").value(t.bytes);
      j.key("bounds").begin_array();
      for (auto b : t.bounds) j.value(static_cast<std::int64_t>(b));
      j.end_array().end_object();
    }
    j.end_array().end_object();
    std::fputs(j.str().c_str(), stdout);
    return kOk;
  }
  std::printf("%s: tiled model (spec/tiles.md), %s, q = %d, origin (%s, %s, %s), step %s\n", in.c_str(),
              kind_name(index.kind), q.bits, g17(q.origin[0]).c_str(), g17(q.origin[1]).c_str(), g17(q.origin[2]).c_str(),
              g17(q.step).c_str());
  std::printf("%zu tiles, %llu points (%llu in the streams with the margin of %lld), %d level(s), %llu bytes, %.3f bits per point\n",
              index.tiles.size(), static_cast<unsigned long long>(index.points),
              static_cast<unsigned long long>(stream_points), static_cast<long long>(index.margin), index.levels,
              static_cast<unsigned long long>(bytes), 8.0 * static_cast<double>(bytes) / static_cast<double>(index.points));
  for (std::size_t k = 0; k < level_bytes.size(); ++k)
    std::printf("  level %zu: prefixes of %llu bytes in all\n", k, static_cast<unsigned long long>(level_bytes[k]));
  std::printf("%16s %10s %10s %10s  %s\n", "file", "points", "streamed", "bytes", "bounds (lattice)");
  for (const auto& t : index.tiles)
    std::printf("%16s %10llu %10llu %10llu  [%lld %lld %lld] - [%lld %lld %lld]\n", t.file.c_str(),
                static_cast<unsigned long long>(t.points), static_cast<unsigned long long>(t.stream_points[0]),
                static_cast<unsigned long long>(t.bytes), static_cast<long long>(t.bounds[0]),
                static_cast<long long>(t.bounds[1]), static_cast<long long>(t.bounds[2]),
                static_cast<long long>(t.bounds[3]), static_cast<long long>(t.bounds[4]),
                static_cast<long long>(t.bounds[5]));
  return kOk;
}

}  // namespace hmc::cli
