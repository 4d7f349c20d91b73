// SPDX-License-Identifier: AGPL-3.0-or-later
// Encoder/decoder round trips and error handling through the public API.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <set>

#include "codec/format.hpp"
#include "container/container.hpp"
#include "hmc/codec.hpp"
#include "samples.hpp"
#include "support/temp_dir.hpp"
#include "support/why.hpp"
#include "util/bytes.hpp"

using namespace hmc;
using namespace hmc::detail;

namespace {

// The expected decoded set, computed here from the definition (bounding-box
// origin, one step = largest extent / (2^q - 1), round to nearest) rather
// than by the encoder's code.
std::set<GridPoint> expected_set(const Mesh& m, int q) {
  Vec3 lo = m.points[0], hi = m.points[0];
  for (const auto& p : m.points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  const double ext = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double step = ext > 0 ? ext / static_cast<double>((1u << q) - 1) : 1.0;
  std::set<GridPoint> s;
  for (const auto& p : m.points) {
    GridPoint g;
    for (int a = 0; a < 3; ++a) {
      const double t = std::round((p[a] - lo[a]) / step);
      g[a] = static_cast<std::uint32_t>(std::min(std::max(t, 0.0), static_cast<double>((1u << q) - 1)));
    }
    s.insert(g);
  }
  return s;
}

Decoded decode_ok(const std::vector<std::uint8_t>& b, const DecodeOptions& o = {}) {
  auto d = decode(b.data(), b.size(), o);
  REQUIRE_MESSAGE(d.ok(), hmc::testgen::why(d));
  return std::move(d).value();
}

Status decode_status(const std::vector<std::uint8_t>& b, const DecodeOptions& o = {}) {
  return decode(b.data(), b.size(), o).status();
}

void check_round_trip(const Mesh& m, int q) {
  auto e = encode(m, EncodeOptions{q, std::nullopt, true});
  REQUIRE_MESSAGE(e.ok(), hmc::testgen::why(e));
  const auto expect = expected_set(m, q);
  auto d = decode_ok(e.value().bytes);
  REQUIRE(d.levels.size() == 1);
  CHECK_FALSE(d.truncated);
  const auto& pts = d.finest().points;
  CHECK(std::is_sorted(pts.begin(), pts.end()));
  CHECK(std::adjacent_find(pts.begin(), pts.end()) == pts.end());
  CHECK(std::set<GridPoint>(pts.begin(), pts.end()) == expect);
  CHECK(e.value().report.distinct_points == expect.size());
  CHECK(e.value().report.duplicates_merged == m.points.size() - expect.size());
  CHECK(d.quantizer.bits == q);
  // Dequantized points lie within half a step (per axis) of an input point.
  for (std::size_t i = 0; i < m.points.size(); i += 1 + m.points.size() / 50) {
    const auto& p = m.points[i];
    double best = 1e300;
    for (const auto& g : pts) {
      auto v = d.quantizer.dequantize(g);
      double worst_axis = std::max({std::abs(v[0] - p[0]), std::abs(v[1] - p[1]), std::abs(v[2] - p[2])});
      best = std::min(best, worst_axis);
    }
    CHECK(best <= d.quantizer.step * 0.5000001 + 1e-12 * std::abs(p[0] + p[1] + p[2]));
  }
}

}  // namespace

TEST_CASE("lossless round trip on generated sets at q = 1, 12 and 21") {
  const std::vector<std::pair<const char*, Mesh>> inputs = {
      {"sphere surface", samples::uv_sphere(20, 30)},
      {"torus", samples::torus(40, 20)},
      {"random ball", samples::random_ball(3000, 1)},
      {"lattice", samples::lattice(9, 7, 5)},
      {"clustered", samples::clustered(6, 300, 2)},
      {"coplanar", samples::coplanar(800, 3)},
      {"collinear", samples::collinear(200, 4)},
      {"one point", samples::all_duplicates(1)},
      {"two points", [] { Mesh m; m.points = {{0, 0, 0}, {1e-3, 2e-3, -5e-4}}; return m; }()},
      {"all duplicates", samples::all_duplicates(500)},
  };
  for (const auto& input : inputs)
    for (int q : {1, 12, 21}) {
      const char* name = input.first;  // a named local: clang cannot capture structured bindings
      CAPTURE(name);
      CAPTURE(q);
      check_round_trip(input.second, q);
    }
}

TEST_CASE("the stream codes the set: input order does not change a byte") {
  Mesh m = samples::random_ball(2000, 9);
  auto a = encode(m).value().bytes;
  samples::Rng rng(3);
  std::shuffle(m.points.begin(), m.points.end(), rng);
  CHECK(encode(m).value().bytes == a);
}

TEST_CASE("encoding on two threads writes the same stream and reports the same levels as on one") {
  struct Case {
    const char* name;
    Mesh mesh;
    std::optional<Kind> kind;
    int levels;
    bool fast;
  };
  const Case cases[] = {
      {"torus surface, 4 levels", samples::torus(48, 20), std::nullopt, 4, false},
      {"open surface, 3 levels", samples::height_field(20, 0.15), std::nullopt, 3, false},
      {"volume, 3 levels", samples::random_ball(700, 4), Kind::volume, 3, false},
      {"points, 3 levels", samples::random_ball(900, 6), Kind::points, 3, false},
      {"torus surface, 3 levels, plain octrees", samples::torus(40, 16), std::nullopt, 3, true},
      {"torus surface, 1 level", samples::torus(40, 16), std::nullopt, 1, false},
  };
  for (const auto& c : cases) {
    CAPTURE(c.name);
    EncodeOptions o;
    o.kind = c.kind;
    o.levels = c.levels;
    o.fast_decode = c.fast;
    const auto one = encode(c.mesh, o);
    REQUIRE(one.ok());
    o.threads = 2;
    const auto two = encode(c.mesh, o);
    REQUIRE(two.ok());
    CHECK(two.value().bytes == one.value().bytes);
    REQUIRE(two.value().report.levels.size() == one.value().report.levels.size());
    CHECK(static_cast<int>(one.value().report.levels.size()) == c.levels);
    for (std::size_t i = 0; i < one.value().report.levels.size(); ++i) {
      CHECK(two.value().report.levels[i].layer_bytes == one.value().report.levels[i].layer_bytes);
      CHECK(two.value().report.levels[i].coder == one.value().report.levels[i].coder);
    }
  }
}

TEST_CASE("duplicates before quantization are merged and counted") {
  Mesh m = samples::lattice(4, 4, 4);
  const auto n = m.points.size();
  for (std::size_t i = 0; i < n; ++i) m.points.push_back(m.points[i]);
  auto e = encode(m).value();
  CHECK(e.report.input_points == 2 * n);
  CHECK(e.report.distinct_points == n);
  CHECK(e.report.duplicates_merged == n);
}

TEST_CASE("kind is detected from the connectivity and can be overridden") {
  CHECK(encode(samples::torus(10, 8)).value().report.kind == Kind::surface);
  CHECK(encode(samples::random_ball(50, 1)).value().report.kind == Kind::points);
  Mesh t = samples::lattice(2, 2, 2);
  t.tetrahedra.push_back({0, 1, 2, 4});
  CHECK(encode(t).value().report.kind == Kind::volume);
  EncodeOptions o;
  o.kind = Kind::volume;
  auto e = encode(samples::random_ball(50, 1), o).value();
  CHECK(decode_ok(e.bytes).kind == Kind::volume);
}

TEST_CASE("triangles turned over at random, or all of them, give the stream of the consistent surface") {
  const Mesh torus = samples::torus(40, 20);
  EncodeOptions o;
  o.levels = 2;
  const auto reference = encode(torus, o).value().bytes;
  samples::Rng rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  Mesh mixed = torus, reversed = torus;
  std::size_t turned = 0;
  for (auto& t : mixed.triangles)
    if (u(rng) < 0.3) std::swap(t[1], t[2]), ++turned;
  for (auto& t : reversed.triangles) std::swap(t[1], t[2]);
  REQUIRE(turned > 100);
  CHECK(encode(mixed, o).value().bytes == reference);
  CHECK(encode(reversed, o).value().bytes == reference);
  // An open sheet too (its reading as a sheet depends on the orientation).
  const Mesh sheet = samples::height_field(16, 0.3);
  const auto sheet_reference = encode(sheet, o).value().bytes;
  Mesh sheet_mixed = sheet;
  for (std::size_t i = 0; i < sheet_mixed.triangles.size(); i += 3)
    std::swap(sheet_mixed.triangles[i][1], sheet_mixed.triangles[i][2]);
  CHECK(encode(sheet_mixed, o).value().bytes == sheet_reference);
}

TEST_CASE("the report notes fewer levels than requested and points that span no volume") {
  auto notes_of = [](const Mesh& m, int levels, std::optional<Kind> kind = std::nullopt) {
    EncodeOptions o;
    o.levels = levels;
    o.kind = kind;
    const auto e = encode(m, o);
    REQUIRE(e.ok());
    return std::make_pair(e.value().report.notes, e.value().report.levels.size());
  };
  auto has = [](const std::string& s, const char* part) { return s.find(part) != std::string::npos; };

  // A flat surface: its triangles are not rebuilt, nor can it be decimated.
  const Mesh flat = samples::height_field(12, 0.0);
  REQUIRE(!flat.triangles.empty());
  for (Kind k : {Kind::surface, Kind::volume}) {
    const auto [notes, levels] = notes_of(flat, 3, k);
    CHECK(levels == 1);
    REQUIRE(notes.size() == 2);
    CHECK(has(notes[0], "span no volume"));
    CHECK(has(notes[0], k == Kind::surface ? "no triangles" : "no tetrahedra"));
    CHECK(has(notes[1], "1 of the 3 levels requested"));
  }
  // One level asked for: only the connectivity note.
  CHECK(notes_of(flat, 1).first.size() == 1);
  // Points carry no connectivity to rebuild; the levels note stays.
  {
    const auto [notes, levels] = notes_of(flat, 3, Kind::points);
    REQUIRE(notes.size() == 1);
    CHECK(has(notes[0], "1 of the 3 levels requested"));
  }

  // A small torus runs out of removable points before 64 levels; the note
  // names the count written.
  {
    const auto [notes, levels] = notes_of(samples::torus(12, 8), 64);
    CHECK(levels < 64);
    REQUIRE(notes.size() == 1);
    CHECK(has(notes[0], (std::to_string(levels) + " of the 64 levels requested").c_str()));
    CHECK(has(notes[0], ("level " + std::to_string(levels - 1) + " is the coarsest").c_str()));
  }
  // Four points cannot be thinned further.
  {
    Mesh four;
    four.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const auto [notes, levels] = notes_of(four, 2);
    CHECK(levels == 1);
    REQUIRE(notes.size() == 1);
    CHECK(has(notes[0], "it has 4 points"));
  }
  // Nothing to say when the request is met by a solid surface.
  const auto [notes, levels] = notes_of(samples::torus(40, 20), 3);
  CHECK(levels == 3);
  CHECK(notes.empty());
}

TEST_CASE("bad encoder input is refused with invalid_argument") {
  CHECK(encode(Mesh{}).status() == Status::invalid_argument);
  Mesh m = samples::random_ball(10, 1);
  m.points[3][1] = std::nan("");
  auto r = encode(m);
  CHECK(r.status() == Status::invalid_argument);
  CHECK(r.error().message.find("point 3") != std::string::npos);
  m.points[3][1] = INFINITY;
  CHECK(encode(m).status() == Status::invalid_argument);
  CHECK(encode(samples::random_ball(10, 1), EncodeOptions{0, std::nullopt, true}).status() == Status::invalid_argument);
  CHECK(encode(samples::random_ball(10, 1), EncodeOptions{22, std::nullopt, true}).status() == Status::invalid_argument);
  Mesh huge;
  huge.points = {{-1e308, 0, 0}, {1e308, 0, 0}};
  CHECK(encode(huge).status() == Status::invalid_argument);
  Mesh badtri = samples::torus(6, 6);
  badtri.triangles.push_back({0, 1, 999});
  CHECK(encode(badtri).status() == Status::invalid_argument);
}

TEST_CASE("tiny and enormous coordinate ranges quantize onto the full grid") {
  for (double scale : {1e-200, 1e-9, 1.0, 1e9, 1e200}) {
    Mesh m = samples::random_ball(300, 5, scale);
    CAPTURE(scale);
    check_round_trip(m, 12);
  }
}

TEST_CASE("a flipped byte anywhere is detected, never decoded into other points") {
  auto b = encode(samples::torus(30, 12)).value().bytes;
  const auto original = decode_ok(b).finest().points;
  for (std::size_t i = 0; i < b.size(); ++i) {
    auto c = b;
    c[i] ^= 0x04;
    auto d = decode(c.data(), c.size());
    CAPTURE(i);
    if (i < 8) {
      CHECK(d.status() == Status::bad_magic);
    } else if (i == 8) {
      CHECK(d.status() == Status::unsupported_version);
    } else if (i == 9) {
      // The minor version is informative: same points.
      REQUIRE(d.ok());
      CHECK(d.value().finest().points == original);
    } else if (d.ok()) {
      // Only a damaged length of the final, empty end chunk can leave every
      // level intact; the decoder then warns that the end is missing.
      CHECK(i >= b.size() - 8);
      CHECK(d.value().finest().points == original);
      CHECK_FALSE(d.value().warning.empty());
    } else {
      CHECK((d.status() == Status::crc_mismatch || d.status() == Status::bad_chunk ||
             d.status() == Status::truncated) == true);
      CHECK_FALSE(d.error().message.empty());
    }
  }
}

TEST_CASE("a CRC error names the chunk and offset") {
  auto b = encode(samples::torus(30, 12)).value().bytes;
  auto view = parse_container(b.data(), b.size(), kEnd);
  for (const auto& c : view.chunks)
    if (c.type == kBaseLayer) b[c.offset + 8 + c.length / 2] ^= 1;  // inside the BASE payload
  auto d = decode(b.data(), b.size());
  REQUIRE(d.status() == Status::crc_mismatch);
  CHECK(d.error().message.find("BASE") != std::string::npos);
  CHECK(d.error().message.find("offset") != std::string::npos);
}

TEST_CASE("truncation: before the level is complete it is an error; after it, the level decodes") {
  auto b = encode(samples::torus(30, 12)).value().bytes;
  auto view = parse_container(b.data(), b.size(), kEnd);
  std::size_t base_end = 0;  // a surface level is complete with its RCON
  for (const auto& c : view.chunks)
    if (c.type == kRecon) base_end = c.offset + kChunkOverhead + c.length;
  REQUIRE(base_end > 0);
  for (std::size_t n = 0; n < b.size(); ++n) {
    std::vector<std::uint8_t> c(b.begin(), b.begin() + static_cast<long>(n));
    auto d = decode(c.data(), c.size());
    CAPTURE(n);
    if (n < base_end) {
      REQUIRE(d.status() == Status::truncated);
      CHECK_FALSE(d.error().message.empty());
    } else {
      // Every declared level is complete; only the end chunk is missing.
      REQUIRE(d.ok());
      CHECK_FALSE(d.value().truncated);
      CHECK(d.value().levels.size() == 1);
      CHECK_FALSE(d.value().warning.empty());
    }
  }
}

namespace {

// Hand-made streams: a valid skeleton whose chunks a test can replace.
struct Chunks {
  std::vector<std::pair<ChunkType, std::vector<std::uint8_t>>> list;
  std::vector<std::uint8_t> bytes() const {
    ContainerWriter w;
    for (const auto& [t, p] : list) w.chunk(t, p);
    return w.finish();
  }
};

Chunks skeleton() {
  auto b = encode(samples::random_ball(100, 4)).value().bytes;
  auto v = parse_container(b.data(), b.size(), kEnd);
  Chunks c;
  for (const auto& ch : v.chunks) c.list.emplace_back(ch.type, std::vector<std::uint8_t>(ch.payload, ch.payload + ch.length));
  return c;
}

std::size_t index_of(const Chunks& c, const ChunkType& t) {
  for (std::size_t i = 0; i < c.list.size(); ++i)
    if (c.list[i].first == t) return i;
  FAIL("chunk not found");
  return 0;
}

}  // namespace

TEST_CASE("hand-made malformed streams get their error class") {
  const Chunks base = skeleton();
  REQUIRE(decode_status(base.bytes()) == Status::ok);

  SUBCASE("q outside 1..21") {
    for (int q : {0, 22, 255}) {
      Chunks c = base;
      c.list[index_of(c, kScalarQuantizer)].second[0] = static_cast<std::uint8_t>(q);
      CHECK(decode_status(c.bytes()) == Status::bad_header);
    }
  }
  SUBCASE("non-positive or non-finite step, non-finite origin") {
    for (double step : {0.0, -1.0, static_cast<double>(INFINITY), static_cast<double>(NAN)}) {
      Chunks c = base;
      ScalarQuantizer q;
      q.step = step;
      c.list[index_of(c, kScalarQuantizer)].second = write_scalar_quantizer(q);
      CHECK(decode_status(c.bytes()) == Status::bad_header);
    }
    Chunks c = base;
    ScalarQuantizer q;
    q.origin[1] = NAN;
    c.list[index_of(c, kScalarQuantizer)].second = write_scalar_quantizer(q);
    CHECK(decode_status(c.bytes()) == Status::bad_header);
  }
  SUBCASE("reserved header flags, unknown kind, trailing header bytes") {
    Chunks c = base;
    c.list[0].second[1] = 2;  // bit 0 is the table form; the rest are reserved
    CHECK(decode_status(c.bytes()) == Status::bad_header);
    c = base;
    c.list[0].second[0] = 3;
    CHECK(decode_status(c.bytes()) == Status::bad_header);
    c = base;
    c.list[0].second.push_back(0);
    CHECK(decode_status(c.bytes()) == Status::bad_header);
  }
  SUBCASE("point counts: zero levels, zero points, over the grid, over the limit") {
    auto head = [](std::vector<std::uint64_t> counts, std::uint64_t levels) {
      ByteWriter w;
      w.u8(0), w.u8(1), w.varint(levels);
      for (auto n : counts) w.varint(n);
      return w.data();
    };
    Chunks c = base;
    c.list[0].second = head({}, 0);
    CHECK(decode_status(c.bytes()) == Status::bad_header);
    c.list[0].second = head({0}, 1);
    CHECK(decode_status(c.bytes()) == Status::bad_header);
    c.list[0].second = head({5, 3}, 2);
    CHECK(decode_status(c.bytes()) == Status::bad_header);
    c.list[0].second = head({1000000000}, 1);
    CHECK(decode_status(c.bytes()) == Status::limit_exceeded);
    // Raising the points limit: the memory limit refuses a billion points
    // (32 GB) before decoding; raising that too, the stream is still
    // refused, without allocating a billion points (the octree runs out of
    // bits or does not match).
    DecodeOptions big;
    big.limits.max_points = 1ull << 40;
    CHECK(decode_status(c.bytes(), big) == Status::limit_exceeded);
    big.limits.max_memory = 1ull << 40;
    CHECK(decode_status(c.bytes(), big) == Status::bad_layer);
    ScalarQuantizer q1;
    q1.bits = 1;
    c.list[index_of(c, kScalarQuantizer)].second = write_scalar_quantizer(q1);
    c.list[0].second = head({9}, 1);
    CHECK(decode_status(c.bytes()) == Status::bad_header);  // a 2^1 grid holds 8 points
    DecodeOptions few;
    few.limits.max_levels = 1;
    c = base;
    c.list[0].second = head({10, 100}, 2);
    CHECK(decode_status(c.bytes(), few) == Status::limit_exceeded);
  }
  SUBCASE("chunk order and count") {
    Chunks c = base;
    std::swap(c.list[0], c.list[1]);
    CHECK(decode_status(c.bytes()) == Status::bad_chunk);  // HEAD not first
    c = base;
    c.list.erase(c.list.begin() + static_cast<long>(index_of(c, kScalarQuantizer)));
    CHECK(decode_status(c.bytes()) == Status::bad_chunk);  // BASE without SQNT
    c = base;
    c.list.insert(c.list.begin() + static_cast<long>(index_of(c, kBaseLayer)), c.list[index_of(c, kBaseLayer)]);
    CHECK(decode_status(c.bytes()) == Status::bad_chunk);  // two BASE
    c = base;
    c.list.insert(c.list.begin() + 1, c.list[0]);
    CHECK(decode_status(c.bytes()) == Status::bad_chunk);  // two HEAD
    c = base;
    c.list.erase(c.list.begin() + static_cast<long>(index_of(c, kBaseLayer)));
    CHECK(decode_status(c.bytes()) == Status::bad_chunk);  // HEND before the level
    c = base;
    c.list.back().second.push_back(0);
    CHECK(decode_status(c.bytes()) == Status::bad_chunk);  // HEND with payload
  }
  SUBCASE("unknown chunks: critical is an error, ancillary is skipped") {
    Chunks c = base;
    c.list.insert(c.list.begin() + 2, {chunk_type("ZZZZ"), {1, 2}});
    CHECK(decode_status(c.bytes()) == Status::bad_chunk);
    c = base;
    c.list.insert(c.list.begin() + 2, {chunk_type("zzzz"), {1, 2}});
    c.list.insert(c.list.end() - 1, {chunk_type("tIME"), {}});
    auto d = decode_ok(c.bytes());
    CHECK(d.finest().points == decode_ok(base.bytes()).finest().points);
  }
  SUBCASE("removed in 0.27: a VQTB chunk and REFN coder 1") {
    // VQTB (the vector quantizer's codebook) is no longer a known chunk: as
    // any unknown critical chunk, it is bad_chunk wherever it stands.
    const std::vector<std::uint8_t> vqtb{3, 1, 2, 3, 4};  // dimension 3, one entry: a valid 0.26 table
    Chunks c = base;
    c.list.insert(c.list.begin() + static_cast<long>(index_of(c, kBaseLayer)), {chunk_type("VQTB"), vqtb});
    CHECK(decode_status(c.bytes()) == Status::bad_chunk);
    // A refinement layer of coder 1 is an unknown coder (bad_layer).
    EncodeOptions two;
    two.kind = Kind::points;
    two.levels = 2;
    const auto bytes = encode(samples::random_ball(300, 3), two).value().bytes;
    const ContainerView v = parse_container(bytes.data(), bytes.size(), kEnd);
    Chunks layered;
    for (const auto& ch : v.chunks)
      layered.list.emplace_back(ch.type, std::vector<std::uint8_t>(ch.payload, ch.payload + ch.length));
    REQUIRE(decode_status(layered.bytes()) == Status::ok);
    layered.list[index_of(layered, kRefinement)].second[0] = 1;
    CHECK(decode_status(layered.bytes()) == Status::bad_layer);
  }
  SUBCASE("base layer: unknown coder, empty, extra bytes, short") {
    Chunks c = base;
    auto& p = c.list[index_of(c, kBaseLayer)].second;
    p[0] = 9;
    CHECK(decode_status(c.bytes()) == Status::bad_layer);
    p.clear();
    CHECK(decode_status(c.bytes()) == Status::bad_layer);
    c = base;
    c.list[index_of(c, kBaseLayer)].second.push_back(0);
    CHECK(decode_status(c.bytes()) == Status::bad_layer);
    c = base;
    c.list[index_of(c, kBaseLayer)].second.resize(c.list[index_of(c, kBaseLayer)].second.size() / 2);
    CHECK(decode_status(c.bytes()) != Status::ok);
  }
  SUBCASE("a declared count that disagrees with the octree") {
    Chunks c = base;
    ByteWriter w;
    w.u8(0), w.u8(1), w.varint(1), w.varint(99);
    c.list[0].second = w.data();
    CHECK(decode_status(c.bytes()) == Status::bad_layer);
  }
}

TEST_CASE("limits: stream size") {
  auto b = encode(samples::random_ball(100, 4)).value().bytes;
  DecodeOptions o;
  o.limits.max_bytes = b.size() - 1;
  CHECK(decode_status(b, o) == Status::limit_exceeded);
}

TEST_CASE("limits: working memory, including a tetrahedralization quadratic in its points") {
  // 2 x 300 points on two skew lines: a stream of about a kilobyte whose
  // Delaunay tetrahedralization has 299^2 = 89,401 tetrahedra.
  Mesh lines;
  for (int i = 0; i < 300; ++i) lines.points.push_back({30.0 * i, 0, 0});
  for (int j = 0; j < 300; ++j) lines.points.push_back({0, 30.0 * j, 9000});
  EncodeOptions eo;
  eo.bits = 14;
  eo.kind = Kind::surface;
  auto e = encode(lines, eo);
  REQUIRE_MESSAGE(e.ok(), hmc::testgen::why(e));
  const auto& b = e.value().bytes;
  CHECK(b.size() < 2000);
  auto d = decode(b.data(), b.size());
  REQUIRE_MESSAGE(d.ok(), hmc::testgen::why(d));
  CHECK(d.value().finest().points.size() == 600);

  // 89,401 tetrahedra at 160 bytes are about 14 MB: 8 MiB is refused, while
  // the tetrahedralization is being built (the native backend; TetGen's
  // worst case, 600 * 597 / 2 tetrahedra, does not fit), not after.
  DecodeOptions small;
  small.limits.max_memory = 8u << 20;
  auto r = decode(b.data(), b.size(), small);
  REQUIRE(!r.ok());
  CHECK(r.error().status == Status::limit_exceeded);
  CHECK(r.error().message.find("delaunay") != std::string::npos);
  // The same on two threads, every level rebuilt or the finest alone.
  for (bool all : {true, false}) {
    DecodeOptions two = small;
    two.threads = 2;
    two.rebuild_coarser_levels = all;
    auto r2t = decode(b.data(), b.size(), two);
    REQUIRE(!r2t.ok());
    CHECK(r2t.error().status == Status::limit_exceeded);
    CHECK(r2t.error().message == r.error().message);
  }
  // Points only: no tetrahedralization, so 8 MiB is plenty.
  small.reconstruct = false;
  CHECK(decode_status(b, small) == Status::ok);
  // 64 MiB: the native backend runs with room to spare and gives the same
  // simplices as TetGen under the default limit.
  DecodeOptions roomy;
  roomy.limits.max_memory = 64u << 20;
  auto r2 = decode(b.data(), b.size(), roomy);
  REQUIRE_MESSAGE(r2.ok(), hmc::testgen::why(r2));
  CHECK(r2.value().finest().triangles == d.value().finest().triangles);
  // A limit below the points' own share refuses the level before decoding it.
  DecodeOptions tiny;
  tiny.limits.max_memory = 600 * 32 - 1;
  tiny.reconstruct = false;
  auto r3 = decode(b.data(), b.size(), tiny);
  REQUIRE(!r3.ok());
  CHECK(r3.error().status == Status::limit_exceeded);
  CHECK(r3.error().message.find("level 0 (600 points)") != std::string::npos);
}

// A 4-level torus stream and the smallest max_memory at which one thread
// decodes it (hi; lo = hi - 1 fails), every level rebuilt or the finest
// alone.
struct LimitSweep {
  explicit LimitSweep(bool every_level) : all(every_level) {
    EncodeOptions eo;
    eo.levels = 4;
    auto e = encode(samples::torus(48, 20), eo);
    REQUIRE(e.ok());
    bytes = std::move(e.value().bytes);
    REQUIRE(!run(lo, 1).ok());
    REQUIRE(run(hi, 1).ok());
    while (hi - lo > 1) {
      const std::uint64_t mid = lo + (hi - lo) / 2;
      (run(mid, 1).ok() ? hi : lo) = mid;
    }
  }
  Result<Decoded> run(std::uint64_t max_memory, unsigned threads) const {
    DecodeOptions o;
    o.limits.max_memory = max_memory;
    o.rebuild_coarser_levels = all;
    o.threads = threads;
    return decode(bytes.data(), bytes.size(), o);
  }
  bool all;
  std::vector<std::uint8_t> bytes;
  std::uint64_t lo = 1, hi = 64u << 20;
};

TEST_CASE("limits: finest level alone on two threads, coarser levels tetrahedralized ahead") {
  // With rebuild_coarser_levels off and two threads, a helper tetrahedralizes
  // the coarser levels while the finer levels' points decode, and the finest
  // level's tetrahedralization is refined from that. It is speculative: at
  // every memory limit the outcome must be that of one thread. The limits
  // tried are those around the smallest that one thread decodes with.
  const LimitSweep sweep(false);
  const auto run = [&](std::uint64_t m, unsigned threads) { return sweep.run(m, threads); };
  const std::uint64_t lo = sweep.lo, hi = sweep.hi;
  const auto ref = run(hi, 1).value();
  REQUIRE(ref.levels.size() == 4);
  REQUIRE_FALSE(ref.finest().triangles.empty());
  std::size_t failed = 0;
  for (std::uint64_t m : {lo - 1000, lo, hi, hi + 1000, hi + 10000, hi + 100000, std::uint64_t{64} << 20}) {
    CAPTURE(m);
    const auto a = run(m, 1);
    const auto t = run(m, 2);
    REQUIRE(a.ok() == t.ok());
    if (!a.ok()) {
      ++failed;
      CHECK(t.error().message == a.error().message);
      continue;
    }
    CHECK(t.value().finest().triangles == ref.finest().triangles);
    CHECK(t.value().levels.size() == 4);
  }
  CHECK(failed == 2);
}

TEST_CASE("limits: every level rebuilt on two threads, refinement layers decoded ahead") {
  // With two threads and every level rebuilt, a helper decodes the
  // refinement layers' points ahead once the base layer is decoded (where
  // the limit leaves room for them beside the finest level's
  // tetrahedralization), and reconstructs each level while the next one is
  // tetrahedralized. At every limit around the smallest that one thread
  // decodes with, two threads must decode the same levels wherever one does
  // (they may decode where one fails, codec.hpp, DecodeOptions::threads,
  // never the reverse) and fail with the same status otherwise (the room a
  // tetrahedralization gets, which the message quotes, may differ while a
  // reconstruction in flight still holds the coarser level's). Before a
  // reconstruction in flight was waited for where its bytes decide, two
  // threads failed at some limits that one decodes with.
  const LimitSweep sweep(true);
  const auto run = [&](std::uint64_t m, unsigned threads) { return sweep.run(m, threads); };
  const std::uint64_t lo = sweep.lo, hi = sweep.hi;
  const auto ref = run(hi, 1).value();
  REQUIRE(ref.levels.size() == 4);
  std::size_t failed = 0;
  for (std::uint64_t m : {lo / 2, lo - 1000, lo, hi, hi + 1000, hi + 10000, hi + 100000, std::uint64_t{2} << 20,
                          std::uint64_t{64} << 20}) {
    CAPTURE(m);
    const auto a = run(m, 1);
    const auto t = run(m, 2);
    if (!a.ok()) {
      ++failed;
      if (!t.ok()) CHECK(t.error().status == a.error().status);
      continue;
    }
    REQUIRE(t.ok());
    REQUIRE(t.value().levels.size() == 4);
    for (std::size_t i = 0; i < 4; ++i) {
      CHECK(t.value().levels[i].points == ref.levels[i].points);
      CHECK(t.value().levels[i].triangles == ref.levels[i].triangles);
    }
  }
  CHECK(failed == 3);
}

TEST_CASE("inspect lists chunks and levels without decoding layers") {
  auto e = encode(samples::torus(30, 12)).value();
  auto i = inspect(e.bytes.data(), e.bytes.size());
  REQUIRE(i.ok());
  const auto& s = i.value();
  REQUIRE(s.chunks.size() == 6);
  CHECK(s.chunks[0].type == "HEAD");
  CHECK(s.chunks[2].type == "info");
  CHECK(s.chunks[3].type == "BASE");
  CHECK(s.chunks[4].type == "RCON");
  CHECK_FALSE(s.chunks[2].critical);
  CHECK(s.chunks.back().type == "HEND");
  REQUIRE(s.levels.size() == 1);
  CHECK(s.levels[0].points == e.report.distinct_points);
  CHECK(s.levels[0].stream_bytes == e.report.levels[0].stream_bytes);
  CHECK(s.total_bytes == e.bytes.size());
  CHECK_FALSE(s.truncated);
}

TEST_CASE("the info chunk carries encoder statistics and can be omitted") {
  Mesh m = samples::all_duplicates(7);
  auto d = decode_ok(encode(m).value().bytes);
  bool found = false;
  for (const auto& [k, v] : d.info)
    if (k == "duplicates_merged") found = (v == "6");
  CHECK(found);
  EncodeOptions o;
  o.write_info = false;
  CHECK(decode_ok(encode(m, o).value().bytes).info.empty());
  // Without duplicates the point counts are the stream's own: only the encoder.
  const auto plain = decode_ok(encode(samples::torus(12, 8)).value().bytes);
  REQUIRE(plain.info.size() == 1);
  CHECK(plain.info[0].first == "encoder");
  CHECK(plain.info[0].second.rfind("hmc ", 0) == 0);
}
