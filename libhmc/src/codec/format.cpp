// SPDX-License-Identifier: AGPL-3.0-or-later
#include "codec/format.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "entropy/huffman.hpp"
#include "entropy/rice.hpp"
#include "util/bytes.hpp"
#include "util/error.hpp"

namespace hmc::detail {

namespace {

void expect_consumed(const ByteReader& r, const ChunkView& c) {
  if (!r.at_end())
    fail(Status::bad_header, to_string(c.type) + ": " + std::to_string(r.remaining()) +
                                 " unexpected byte(s) at the end of the payload");
}

}  // namespace

bool is_known_chunk(const ChunkType& t) {
  return t == kHead || t == kScalarQuantizer || t == kBaseLayer || t == kRefinement ||
         t == kRecon || t == kEnd || t == kInfo;
}

std::vector<std::uint8_t> Header::write() const {
  ByteWriter w;
  w.u8(static_cast<std::uint8_t>(kind));
  w.u8(tables == TableForm::deltas ? 1 : 0);  // flags: bit 0, delta tables
  w.varint(points.size());
  for (std::uint64_t n : points) w.varint(n);
  return std::move(w.data());
}

Header Header::read(const ChunkView& c, const DecodeLimits& limits) {
  ByteReader r(c.payload, c.length, Status::bad_header, "HEAD");
  Header h;
  const std::uint8_t kind = r.u8();
  if (kind > 2) fail(Status::bad_header, "HEAD: kind " + std::to_string(kind) + " is not 0, 1 or 2");
  h.kind = static_cast<Kind>(kind);
  const std::uint8_t flags = r.u8();
  if (flags > 1) fail(Status::bad_header, "HEAD: reserved flag bits are set (flags " + std::to_string(flags) + ")");
  h.tables = flags & 1 ? TableForm::deltas : TableForm::nibbles;
  const std::uint64_t levels = r.varint();
  if (levels < 1 || levels > kMaxLevels)
    fail(Status::bad_header, "HEAD: level count " + std::to_string(levels) + " is outside 1..64");
  if (levels > limits.max_levels)
    fail(Status::limit_exceeded, "HEAD: " + std::to_string(levels) + " levels, over the limit of " +
                                     std::to_string(limits.max_levels));
  std::uint64_t prev = 0;
  for (std::uint64_t i = 0; i < levels; ++i) {
    const std::uint64_t n = r.varint();
    if (n <= prev)
      fail(Status::bad_header, "HEAD: point count of level " + std::to_string(levels - 1 - i) + " (" +
                                   std::to_string(n) + ") must exceed the coarser level's (" + std::to_string(prev) + ")");
    h.points.push_back(n);
    prev = n;
  }
  if (prev > limits.max_points)
    fail(Status::limit_exceeded, "HEAD: " + std::to_string(prev) + " points, over the limit of " +
                                     std::to_string(limits.max_points));
  expect_consumed(r, c);
  return h;
}

std::vector<std::uint8_t> write_scalar_quantizer(const ScalarQuantizer& q) {
  ByteWriter w;
  w.u8(static_cast<std::uint8_t>(q.bits));
  for (double o : q.origin) w.f64(o);
  w.f64(q.step);
  return std::move(w.data());
}

ScalarQuantizer read_scalar_quantizer(const ChunkView& c) {
  ByteReader r(c.payload, c.length, Status::bad_header, "SQNT");
  ScalarQuantizer q;
  q.bits = r.u8();
  if (q.bits < kMinBits || q.bits > kMaxBits)
    fail(Status::bad_header, "SQNT: q = " + std::to_string(q.bits) + " is outside 1..21");
  for (double& o : q.origin) {
    o = r.f64();
    if (!std::isfinite(o)) fail(Status::bad_header, "SQNT: origin is not finite");
  }
  q.step = r.f64();
  if (!std::isfinite(q.step) || !(q.step > 0)) fail(Status::bad_header, "SQNT: step is not a finite positive number");
  expect_consumed(r, c);
  return q;
}

namespace {

void write_index_list(ByteWriter& w, const std::vector<std::uint32_t>& list) {
  w.varint(list.size());
  std::uint64_t next = 0;  // smallest value the next entry may take
  for (std::uint32_t v : list) {
    w.varint(v - next);
    next = std::uint64_t{v} + 1;
  }
}

std::vector<std::uint32_t> read_index_list(ByteReader& r, std::uint64_t bound, const char* what) {
  const std::uint64_t count = r.varint();
  // Each entry takes at least one byte, and entries are distinct below `bound`.
  if (count > r.remaining() || count > bound)
    fail(Status::bad_layer, std::string("RCON: ") + what + " count " + std::to_string(count) + " is impossible here");
  std::vector<std::uint32_t> list(count);
  std::uint64_t next = 0;
  for (auto& v : list) {
    const std::uint64_t x = next + r.varint();
    if (x >= bound || x < next)
      fail(Status::bad_layer, std::string("RCON: ") + what + " index " + std::to_string(x) + " out of range");
    v = static_cast<std::uint32_t>(x);
    next = x + 1;
  }
  return list;
}

// Every RCON index and rank is below 2^32 - 1 (spec section 10).
constexpr std::uint64_t kIndexBound = 0xffffffffu;
// Largest alphabet of a group of classes (spec section 10).
constexpr std::uint64_t kMaxClassAlphabet = 4096;

std::uint32_t class_alphabet(std::uint32_t classes, int group) {
  std::uint64_t a = 1;
  for (int i = 0; i < group; ++i) a *= classes;
  return a > kMaxClassAlphabet ? 0 : static_cast<std::uint32_t>(a);
}

// Symbols of the class stream with `group` classes per symbol.
std::vector<std::uint32_t> class_symbols(const std::vector<std::uint8_t>& cls, std::uint32_t classes, int group) {
  std::vector<std::uint32_t> sym((cls.size() + static_cast<std::size_t>(group) - 1) / static_cast<std::size_t>(group), 0);
  for (std::size_t b = 0; b < sym.size(); ++b) {
    std::uint32_t s = 0;
    for (int i = group - 1; i >= 0; --i) {
      const std::size_t v = b * static_cast<std::size_t>(group) + static_cast<std::size_t>(i);
      s = s * classes + (v < cls.size() ? cls[v] : 0u);
    }
    sym[b] = s;
  }
  return sym;
}

// Classes in groups (spec section 10, compact form): the group size that
// gives the shortest stream, then one code over the groups.
std::vector<std::uint8_t> write_class_groups(const std::vector<std::uint8_t>& cls, std::uint32_t classes) {
  std::vector<std::uint8_t> best;
  for (int group = 1; group <= 8; ++group) {
    const std::uint32_t alphabet = class_alphabet(classes, group);
    if (alphabet == 0) break;
    const auto sym = class_symbols(cls, classes, group);
    std::vector<std::uint64_t> freq(alphabet, 0);
    for (auto s : sym) ++freq[s];
    const auto code = HuffmanCode::from_frequencies(freq);
    BitWriter bw;
    bw.put(static_cast<std::uint32_t>(group - 1), 3);
    code.write(bw);
    for (auto s : sym) code.encode(bw, s);
    auto bytes = bw.finish();
    if (best.empty() || bytes.size() < best.size()) best = std::move(bytes);
  }
  return best;
}

std::vector<std::uint8_t> read_class_groups(BitReader& br, std::uint32_t classes, std::uint64_t points, TableForm form) {
  const int group = static_cast<int>(br.get(3)) + 1;
  const std::uint32_t alphabet = class_alphabet(classes, group);
  if (alphabet == 0)
    fail(Status::bad_layer, "RCON: " + std::to_string(classes) + " classes in groups of " + std::to_string(group) +
                                " make an alphabet over 4096");
  const auto code = HuffmanCode::read(br, alphabet, "RCON class table", form);
  std::vector<std::uint8_t> cls(points);
  for (std::uint64_t b = 0; b * static_cast<std::uint64_t>(group) < points; ++b) {
    std::uint32_t s = code.decode(br);
    for (int i = 0; i < group; ++i, s /= classes) {
      const std::uint64_t v = b * static_cast<std::uint64_t>(group) + static_cast<std::uint64_t>(i);
      if (v < points) {
        cls[v] = static_cast<std::uint8_t>(s % classes);
      } else if (s % classes != 0) {
        fail(Status::bad_layer, "RCON: a class group gives a class to a point beyond the last");
      }
    }
  }
  return cls;
}

// A sorted list of distinct indices as one context of spec 10.2: a count,
// and the gaps between entries in a Rice code whose parameter the encoder
// picks (the toggle ranks of each context, the points of a class list).
// `inverted` (a neighbour context's list, spec 0.24): the count is sent as
// 2·count + inverted.
void write_rice_list(BitWriter& bw, const std::vector<std::uint32_t>& list, int inverted = -1) {
  bw.exp_golomb(static_cast<std::uint32_t>(inverted < 0 ? list.size() : 2 * list.size() + static_cast<std::size_t>(inverted)));
  if (list.empty()) return;
  const auto gaps = index_gaps(list);
  const int best_k = best_rice(gaps).k;
  bw.put(static_cast<std::uint32_t>(best_k), 5);
  for (auto g : gaps) {
    for (std::uint64_t q = g >> best_k; q > 0; --q) bw.put(1, 1);
    bw.put(0, 1);
    if (best_k > 0) bw.put(static_cast<std::uint32_t>(g & ((std::uint64_t{1} << best_k) - 1)), best_k);
  }
}

// Reads one list written by write_rice_list; `what` names it in errors.
std::vector<std::uint32_t> read_rice_list(BitReader& br, const std::string& what, bool* inverted = nullptr) {
  std::uint64_t count = br.exp_golomb();
  if (inverted) *inverted = (count & 1) != 0, count >>= 1;
  // Each entry takes at least one bit.
  if (count > br.bits_left())
    fail(Status::bad_layer, "RCON: " + what + " count " + std::to_string(count) + " is larger than the bits left");
  std::vector<std::uint32_t> list;
  if (count == 0) return list;
  const int k = static_cast<int>(br.get(5));
  list.resize(count);
  std::uint64_t next = 0;
  for (auto& v : list) {
    std::uint64_t q = 0;
    while (br.get(1) == 1)
      if ((++q << k) >= kIndexBound) fail(Status::bad_layer, "RCON: " + what + " out of range");
    const std::uint64_t x = next + (q << k) + (k > 0 ? br.get(k) : 0u);
    if (x >= kIndexBound) fail(Status::bad_layer, "RCON: " + what + " " + std::to_string(x) + " out of range");
    v = static_cast<std::uint32_t>(x);
    next = x + 1;
  }
  return list;
}

// Toggle ranks per context (spec section 10, compact form): one list for
// each of the first `contexts` contexts.
std::vector<std::uint8_t> write_toggle_ranks(const std::array<std::vector<std::uint32_t>, kToggleContexts>& ranks,
                                             int contexts) {
  BitWriter bw;
  for (int j = 0; j < kToggleContexts; ++j) {
    if (j < contexts) write_rice_list(bw, ranks[static_cast<std::size_t>(j)]);
    else if (!ranks[static_cast<std::size_t>(j)].empty())
      fail(Status::internal_error,
           "RCON: toggle ranks in context " + std::to_string(j) + " of " + std::to_string(contexts));
  }
  return bw.finish();
}

// The lists of the neighbour contexts (flag bit 7): one for each of them,
// its count carrying whether it is inverted.
std::vector<std::uint8_t> write_neighbour_lists(const ReconParams& p) {
  if (p.neighbour_lists.size() != kNeighbourContexts || p.neighbour_inverted.size() != kNeighbourContexts)
    fail(Status::internal_error, "RCON: neighbour contexts without their lists");
  BitWriter bw;
  for (std::size_t j = 0; j < kNeighbourContexts; ++j)
    write_rice_list(bw, p.neighbour_lists[j], p.neighbour_inverted[j] ? 1 : 0);
  return bw.finish();
}

void read_neighbour_lists(BitReader& br, ReconParams& p) {
  p.neighbour_lists.resize(kNeighbourContexts);
  p.neighbour_inverted.assign(kNeighbourContexts, 0);
  for (std::size_t j = 0; j < kNeighbourContexts; ++j) {
    bool inverted = false;
    p.neighbour_lists[j] = read_rice_list(br, "toggle rank", &inverted);
    p.neighbour_inverted[j] = inverted ? 1 : 0;
  }
}

std::array<std::vector<std::uint32_t>, kToggleContexts> read_toggle_ranks(BitReader& br, int contexts) {
  std::array<std::vector<std::uint32_t>, kToggleContexts> ranks;
  for (int j = 0; j < contexts; ++j) ranks[static_cast<std::size_t>(j)] = read_rice_list(br, "toggle rank");
  return ranks;
}

// Classes as a list (spec 10.1, class_list): the common class, the points
// of the other classes as one list of 10.2 and, with three classes or more,
// one code for which other class each listed point has.
std::vector<std::uint8_t> write_class_list(const std::vector<std::uint8_t>& cls, std::uint32_t classes) {
  std::vector<std::uint64_t> count(classes, 0);
  for (auto c : cls) ++count[c];
  const auto common = static_cast<std::uint32_t>(std::max_element(count.begin(), count.end()) - count.begin());
  std::vector<std::uint32_t> others;
  std::vector<std::uint32_t> sym;
  for (std::size_t v = 0; v < cls.size(); ++v)
    if (cls[v] != common) others.push_back(static_cast<std::uint32_t>(v)), sym.push_back(cls[v] - (cls[v] > common));
  BitWriter bw;
  bw.put(common, 6);
  write_rice_list(bw, others);
  if (classes > 2) {
    std::vector<std::uint64_t> freq(classes - 1, 0);
    for (auto s : sym) ++freq[s];
    const auto code = HuffmanCode::from_frequencies(freq);
    code.write(bw);
    for (auto s : sym) code.encode(bw, s);
  }
  return bw.finish();
}

std::vector<std::uint8_t> read_class_list(BitReader& br, std::uint32_t classes, std::uint64_t points, TableForm form) {
  const std::uint32_t common = br.get(6);
  if (common >= classes)
    fail(Status::bad_layer, "RCON: common class " + std::to_string(common) + " of " + std::to_string(classes));
  const auto others = read_rice_list(br, "class list entry");
  if (!others.empty() && others.back() >= points)
    fail(Status::bad_layer, "RCON: class list entry " + std::to_string(others.back()) + " is not below the " +
                                std::to_string(points) + " points");
  std::vector<std::uint8_t> cls(points, static_cast<std::uint8_t>(common));
  if (classes == 2) {
    for (auto v : others) cls[v] = static_cast<std::uint8_t>(1 - common);
  } else {
    const auto code = HuffmanCode::read(br, classes - 1, "RCON class list table", form);
    for (auto v : others) {
      const std::uint32_t s = code.decode(br);
      cls[v] = static_cast<std::uint8_t>(s + (s >= common));
    }
  }
  return cls;
}

}  // namespace

std::vector<std::uint8_t> write_recon(const ReconParams& p) {
  ByteWriter w;
  // The compact form's classes: in groups or as a list, whichever is shorter.
  std::vector<std::uint8_t> classes;
  bool class_list = false;
  if (p.compact && p.multipliers.size() > 1) {
    const auto k = static_cast<std::uint32_t>(p.multipliers.size());
    classes = write_class_groups(p.vertex_class, k);
    auto list = write_class_list(p.vertex_class, k);
    if (list.size() < classes.size()) classes = std::move(list), class_list = true;
  }
  if ((p.candidate_contexts && !p.compact) || (p.vertex_contexts && !p.candidate_contexts) ||
      (p.neighbour_contexts && !p.vertex_contexts))
    fail(Status::internal_error, "RCON: toggle contexts without the flags they need");
  w.u8(static_cast<std::uint8_t>((p.peel ? 1 : 0) | (p.repair ? 2 : 0) | (p.compact ? 4 : 0) | (p.border_delta ? 8 : 0) |
                                 (class_list ? 16 : 0) | (p.candidate_contexts ? 32 : 0) |
                                 (p.vertex_contexts ? 64 : 0) | (p.neighbour_contexts ? 128 : 0)));
  w.u8(static_cast<std::uint8_t>(p.scale_rank));
  std::uint8_t mask = 0;
  for (int i = 0; i < kFilterCount; ++i)
    if (p.filters[static_cast<std::size_t>(i)]) mask = static_cast<std::uint8_t>(mask | (1u << i));
  if (p.seal) mask = static_cast<std::uint8_t>(mask | (1u << kSealBit));
  w.u8(mask);
  for (int i = 0; i < kFilterCount; ++i)
    if (p.filters[static_cast<std::size_t>(i)]) w.varint(p.filters[static_cast<std::size_t>(i)]);
  if (p.seal) {
    for (int ax = 0; ax < 3; ++ax)
      if (p.seal_box[ax] >= p.seal_box[3 + ax] || p.seal_box[3 + ax] > kSealBound)
        fail(Status::internal_error, "RCON: an empty or oversized seal box");
    for (std::uint32_t b : p.seal_box) w.varint(b);
  }
  w.varint(p.multipliers.size());
  for (std::uint32_t m : p.multipliers) w.varint(m);
  if (p.multipliers.size() > 1) {
    if (p.compact) {
      w.bytes(classes);
    } else {
      std::vector<std::uint64_t> freq(p.multipliers.size(), 0);
      for (auto c : p.vertex_class) ++freq[c];
      const auto code = HuffmanCode::from_frequencies(freq);
      BitWriter bw;
      code.write(bw);
      for (auto c : p.vertex_class) code.encode(bw, c);
      w.bytes(bw.finish());
    }
  }
  // Border vertices are only meaningful for surfaces; the list is empty otherwise.
  write_index_list(w, p.border);
  if (p.compact) {
    write_index_list(w, p.drops);
    w.bytes(p.neighbour_contexts ? write_neighbour_lists(p) : write_toggle_ranks(p.toggle_ranks, toggle_context_count(p)));
  } else {
    write_index_list(w, p.toggles);
    write_index_list(w, p.drops);
  }
  return std::move(w.data());
}

ReconParams read_recon(const ChunkView& c, std::uint64_t points, TableForm form) {
  ByteReader r(c.payload, c.length, Status::bad_layer, "RCON");
  ReconParams p;
  const std::uint8_t flags = r.u8();
  p.peel = flags & 1;
  p.repair = (flags & 2) != 0;
  p.compact = (flags & 4) != 0;
  p.border_delta = (flags & 8) != 0;
  const bool class_list = (flags & 16) != 0;
  if (class_list && !p.compact) fail(Status::bad_layer, "RCON: a class list (flag bit 4) without the compact form");
  p.candidate_contexts = (flags & 32) != 0;
  if (p.candidate_contexts && !p.compact)
    fail(Status::bad_layer, "RCON: candidate contexts (flag bit 5) without the compact form");
  p.vertex_contexts = (flags & 64) != 0;
  if (p.vertex_contexts && !p.candidate_contexts)
    fail(Status::bad_layer, "RCON: vertex contexts (flag bit 6) without candidate contexts (bit 5)");
  p.neighbour_contexts = (flags & 128) != 0;
  if (p.neighbour_contexts && !p.vertex_contexts)
    fail(Status::bad_layer, "RCON: neighbour contexts (flag bit 7) without vertex contexts (bit 6)");
  p.scale_rank = r.u8();
  if (p.scale_rank < 1 || p.scale_rank > kMaxScaleRank)
    fail(Status::bad_layer, "RCON: scale rank " + std::to_string(p.scale_rank) + " is outside 1..64");
  const std::uint8_t mask = r.u8();
  if (mask >> (kSealBit + 1)) fail(Status::bad_layer, "RCON: reserved filter_mask bit 7 is set");
  for (int i = 0; i < kFilterCount; ++i) {
    if (!(mask & (1u << i))) continue;
    const std::uint64_t t = r.varint();
    if (t < 1 || t > 65535 || (i == kLone && t != 1))
      fail(Status::bad_layer, "RCON: filter " + std::to_string(i) + " threshold " + std::to_string(t) + " is out of range");
    p.filters[static_cast<std::size_t>(i)] = static_cast<std::uint32_t>(t);
  }
  p.seal = (mask >> kSealBit) & 1u;
  if (p.seal) {
    std::array<std::uint64_t, 6> b{};
    for (auto& v : b) v = r.varint();
    for (int ax = 0; ax < 3; ++ax)
      if (b[ax] >= b[3 + ax] || b[3 + ax] > kSealBound)
        fail(Status::bad_layer, "RCON: seal box axis " + std::to_string(ax) + " [" + std::to_string(b[ax]) + ", " +
                                    std::to_string(b[3 + ax]) + ") is empty or beyond 2^21");
    for (int i = 0; i < 6; ++i) p.seal_box[static_cast<std::size_t>(i)] = static_cast<std::uint32_t>(b[static_cast<std::size_t>(i)]);
  }
  const std::uint64_t k = r.varint();
  if (k < 1 || k > kMaxClasses) fail(Status::bad_layer, "RCON: class count " + std::to_string(k) + " is outside 1..64");
  p.multipliers.clear();
  for (std::uint64_t i = 0; i < k; ++i) {
    const std::uint64_t m = r.varint();
    if (m < 1 || m > 65535) fail(Status::bad_layer, "RCON: multiplier " + std::to_string(m) + " is outside 1..65535");
    if (!p.multipliers.empty() && m <= p.multipliers.back())
      fail(Status::bad_layer, "RCON: multipliers must increase");
    p.multipliers.push_back(static_cast<std::uint32_t>(m));
  }
  if (k > 1) {
    BitReader br(r.here(), r.remaining(), "RCON classes");
    if (p.compact) {
      p.vertex_class = class_list ? read_class_list(br, static_cast<std::uint32_t>(k), points, form)
                                  : read_class_groups(br, static_cast<std::uint32_t>(k), points, form);
    } else {
      const auto code = HuffmanCode::read(br, static_cast<std::uint32_t>(k), "RCON class table", form);
      p.vertex_class.resize(points);
      for (auto& v : p.vertex_class) v = static_cast<std::uint8_t>(code.decode(br));
    }
    r.skip(br.align());
  }
  p.border = read_index_list(r, points, "border");
  if (p.compact) {
    p.drops = read_index_list(r, kIndexBound, "dropped face");
    BitReader br(r.here(), r.remaining(), "RCON toggles");
    if (p.neighbour_contexts) read_neighbour_lists(br, p);
    else p.toggle_ranks = read_toggle_ranks(br, toggle_context_count(p));
    br.expect_end();
    return p;
  }
  p.toggles = read_index_list(r, kIndexBound, "toggle");
  p.drops = read_index_list(r, kIndexBound, "dropped face");
  if (!r.at_end()) fail(Status::bad_layer, "RCON: " + std::to_string(r.remaining()) + " unexpected byte(s) at the end");
  return p;
}

}  // namespace hmc::detail
