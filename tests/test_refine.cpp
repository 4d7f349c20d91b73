// SPDX-License-Identifier: AGPL-3.0-or-later
// Refinement layer: round trips over many splits of the sample sets, order
// independence, an independent decoder written from the spec text, and
// malformed streams.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <tuple>

#include "entropy/huffman.hpp"
#include "hmc/codec.hpp"
#include "pointset/lattice_neighbours.hpp"
#include "pointset/octree.hpp"
#include "entropy/paired.hpp"
#include "pointset/plane_rank.hpp"
#include "pointset/refine.hpp"
#include "samples.hpp"
#include "support/why.hpp"
#include "util/kdtree.hpp"
#include "util/morton.hpp"
#include "util/radix_sort.hpp"

using namespace hmc;
using namespace hmc::detail;

namespace {

using Points = std::vector<GridPoint>;

Status status_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const StreamError& e) {
    return e.error().status;
  }
  return Status::ok;
}

Points quantize(const Mesh& m, int q) {
  EncodeOptions o;
  o.bits = q;
  o.kind = Kind::points;
  o.write_info = false;
  auto e = encode(m, o);
  REQUIRE_MESSAGE(e.ok(), hmc::testgen::why(e));
  return e.value().points;
}

Points sorted(Points p) {
  sort_canonical(p);
  return p;
}

// Refinement parameters with the given neighbours and classes, the rest
// default (no plane contexts, no gap weights).
RefinementParams params(int neighbours, int classes) {
  RefinementParams p;
  p.neighbours = neighbours;
  p.classes = classes;
  return p;
}

struct Split {
  Points coarse, added;
};

// `bytes` decode to the added points as coder `right`; read as coder
// `wrong`, whose header differs, they fail or give another set.
void check_coders(const std::vector<std::uint8_t>& bytes, const Split& s, int q, RefineCoder right,
                  RefineCoder wrong) {
  CHECK(decode_refinement(bytes.data(), bytes.size(), q, s.coarse, s.added.size(), TableForm::deltas, right) ==
        sorted(s.added));
  Points other;
  const Status st = status_of([&] {
    other = decode_refinement(bytes.data(), bytes.size(), q, s.coarse, s.added.size(), TableForm::deltas, wrong);
  });
  CHECK((st == Status::bad_layer || st == Status::bad_huffman_table || (st == Status::ok && other != sorted(s.added))));
}

// Bits [at, at + n) of a layer's bit stream (its header fields), most
// significant first.
std::uint32_t header_field(const std::vector<std::uint8_t>& bytes, std::size_t at, int n) {
  std::uint32_t v = 0;
  for (std::size_t i = at; i < at + static_cast<std::size_t>(n); ++i) v = (v << 1) | ((bytes[i / 8] >> (7 - i % 8)) & 1u);
  return v;
}

// Puts each point in `added` when pick(i) holds; the coarse part is canonical.
Split split_by(const Points& all, const std::function<bool(std::size_t)>& pick) {
  Split s;
  for (std::size_t i = 0; i < all.size(); ++i) (pick(i) ? s.added : s.coarse).push_back(all[i]);
  sort_canonical(s.coarse);
  return s;
}

Split split_random(const Points& all, double fraction, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::size_t> idx(all.size());
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  std::shuffle(idx.begin(), idx.end(), rng);
  auto n = static_cast<std::size_t>(fraction * static_cast<double>(all.size()));
  n = std::min(std::max<std::size_t>(n, 1), all.size() - 1);
  std::vector<char> added(all.size(), 0);
  for (std::size_t i = 0; i < n; ++i) added[idx[i]] = 1;
  return split_by(all, [&](std::size_t i) { return added[i] != 0; });
}

// ---- An independent decoder, written from spec/refinement-layer.md. It
// searches neighbours by brute force and keeps no state between nodes, so it
// checks the library's neighbour search and its candidate hand-down.
class ReferenceDecoder {
 public:
  ReferenceDecoder(const std::vector<std::uint8_t>& data, int q, const Points& coarse, std::uint64_t n)
      : in_(data.data(), data.size(), "reference"), q_(q), coarse_(coarse), n_(n) {
    for (unsigned v = 1; v < 256; ++v) e_.push_back(v);
    std::stable_sort(e_.begin(), e_.end(), [](unsigned a, unsigned b) { return bits(a) < bits(b); });
    K_ = static_cast<int>(in_.get(4));
    L_ = static_cast<int>(in_.get(2)) + 1;
    table_.assign(static_cast<std::size_t>(q * L_), -1);
    for (int d = 0; d < q; ++d)
      for (int k = 0; k < L_; ++k) {
        const auto slot = static_cast<std::size_t>(d * L_ + k);
        if (in_.get(1)) {
          codes_.push_back(HuffmanCode::read(in_, 255, "reference table"));
          table_[slot] = static_cast<int>(codes_.size()) - 1;
        } else if (d > 0) {
          table_[slot] = table_[slot - static_cast<std::size_t>(L_)];
        }
      }
    visit(0, {0, 0, 0});
    in_.expect_end();
    if (points.size() != n_) fail(Status::bad_layer, "reference: point count");
    sort_canonical(points);
  }
  Points points;

 private:
  static int bits(unsigned v) { return v ? static_cast<int>(v & 1u) + bits(v >> 1) : 0; }

  static std::int64_t shrink(std::int64_t x, int s) { return x < 0 ? -((-x) >> s) : x >> s; }
  template <class It>
  static void reduce(It first, It last, int b) {
    std::int64_t m = 0;
    for (It i = first; i != last; ++i) m = std::max(m, *i < 0 ? -*i : *i);
    int len = 0;
    while (len < 63 && (m >> len) != 0) ++len;
    const int s = std::max(0, len - b);
    for (It i = first; i != last; ++i) *i = shrink(*i, s);
  }

  // The child of `node` (depth d) that holds p, or -1.
  int child_of(const GridPoint& p, const std::array<std::int64_t, 3>& node, int d) const {
    int c = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      const std::int64_t at = std::int64_t{p[a]} >> (q_ - d - 1);
      if ((at >> 1) != node[a]) return -1;
      c = 2 * c + static_cast<int>(at & 1);
    }
    return c;
  }

  void visit(int d, const std::array<std::int64_t, 3>& node) {
    unsigned m = 0;
    for (const GridPoint& p : coarse_)
      if (const int c = child_of(p, node, d); c >= 0) m |= 1u << c;
    const int cls = std::min(bits(m), L_ - 1);
    const int t = table_[static_cast<std::size_t>(d * L_ + cls)];
    if (t < 0) fail(Status::bad_layer, "reference: no table");
    const unsigned rho = e_[codes_[static_cast<std::size_t>(t)].decode(in_)];

    // Neighbours: the k coarse points nearest to the node centre (doubled
    // coordinates), ties by canonical index.
    const std::int64_t h = std::int64_t{1} << (q_ - d);
    std::array<std::int64_t, 3> o{};
    for (std::size_t a = 0; a < 3; ++a) o[a] = 2 * node[a] * h + h;
    std::vector<std::pair<std::int64_t, std::size_t>> by_distance;
    for (std::size_t i = 0; i < coarse_.size(); ++i) {
      std::int64_t d2 = 0;
      for (std::size_t a = 0; a < 3; ++a) d2 += (2 * std::int64_t{coarse_[i][a]} - o[a]) * (2 * std::int64_t{coarse_[i][a]} - o[a]);
      by_distance.emplace_back(d2, i);
    }
    const std::int64_t k = std::min<std::int64_t>(K_, static_cast<std::int64_t>(coarse_.size()));
    std::partial_sort(by_distance.begin(), by_distance.begin() + k, by_distance.end());
    std::array<std::int64_t, 3> S{};
    std::int64_t sxx = 0, syy = 0, szz = 0, sxy = 0, sxz = 0, syz = 0;
    for (std::int64_t i = 0; i < k; ++i) {
      const GridPoint& p = coarse_[by_distance[static_cast<std::size_t>(i)].second];
      const std::int64_t x = 2 * std::int64_t{p[0]}, y = 2 * std::int64_t{p[1]}, z = 2 * std::int64_t{p[2]};
      S[0] += x, S[1] += y, S[2] += z;
      sxx += x * x, syy += y * y, szz += z * z, sxy += x * y, sxz += x * z, syz += y * z;
    }
    std::array<std::int64_t, 6> M{k * sxx - S[0] * S[0], k * syy - S[1] * S[1], k * szz - S[2] * S[2],
                                  k * sxy - S[0] * S[1], k * sxz - S[0] * S[2], k * syz - S[1] * S[2]};
    reduce(M.begin(), M.end(), 31);
    const std::int64_t Mxx = M[0], Myy = M[1], Mzz = M[2], Mxy = M[3], Mxz = M[4], Myz = M[5];
    const std::int64_t Axx = Myy * Mzz - Myz * Myz, Ayy = Mxx * Mzz - Mxz * Mxz, Azz = Mxx * Myy - Mxy * Mxy;
    const std::int64_t Axy = Mxz * Myz - Mxy * Mzz, Axz = Mxy * Myz - Mxz * Myy, Ayz = Mxy * Mxz - Mxx * Myz;
    std::array<std::int64_t, 3> n{Axx, Axy, Axz};
    if (Ayy > Axx && Ayy >= Azz) n = {Axy, Ayy, Ayz};
    else if (Azz > Axx && Azz > Ayy) n = {Axz, Ayz, Azz};
    reduce(n.begin(), n.end(), 20);

    struct Key {
      int coarse_free;
      std::int64_t t, e;
      int c;
      bool operator<(const Key& o) const {
        return std::tie(coarse_free, t, e, c) < std::tie(o.coarse_free, o.t, o.e, o.c);
      }
    };
    std::vector<Key> rank;
    for (int c = 0; c < 8; ++c) {
      std::int64_t dot = 0, len = 0;
      for (std::size_t a = 0; a < 3; ++a) {
        const std::int64_t u = (2 * node[a] + ((c >> (2 - static_cast<int>(a))) & 1)) * h + h / 2;
        const std::int64_t v = k * u - S[a];
        dot += n[a] * v;
        len += v * v;
      }
      rank.push_back({(m >> c) & 1u ? 0 : 1, dot < 0 ? -dot : dot, len, c});
    }
    std::sort(rank.begin(), rank.end());
    unsigned occ = 0;
    for (int r = 0; r < 8; ++r)
      if ((rho >> r) & 1u) occ |= 1u << rank[static_cast<std::size_t>(r)].c;

    for (int c = 0; c < 8; ++c) {
      if (!((occ >> c) & 1u)) continue;
      std::array<std::int64_t, 3> child{};
      for (std::size_t a = 0; a < 3; ++a) child[a] = 2 * node[a] + ((c >> (2 - static_cast<int>(a))) & 1);
      if (d + 1 < q_) {
        visit(d + 1, child);
        continue;
      }
      if ((m >> c) & 1u) fail(Status::bad_layer, "reference: added point is a coarse point");
      if (points.size() == n_) fail(Status::bad_layer, "reference: too many points");
      points.push_back({static_cast<std::uint32_t>(child[0]), static_cast<std::uint32_t>(child[1]),
                        static_cast<std::uint32_t>(child[2])});
    }
  }

  BitReader in_;
  int q_;
  const Points& coarse_;
  std::uint64_t n_;
  int K_ = 0, L_ = 1;
  std::vector<unsigned> e_;
  std::vector<HuffmanCode> codes_;
  std::vector<int> table_;
};

// Encodes, decodes with the library and (for small sets) with the reference
// decoder; returns the stream.
std::vector<std::uint8_t> round_trip(const Points& coarse, const Points& added, int q,
                                     const RefinementParams* params = nullptr) {
  const auto bytes = params ? encode_refinement(coarse, added, q, *params) : encode_refinement(coarse, added, q);
  const Points back = decode_refinement(bytes.data(), bytes.size(), q, coarse, added.size());
  CHECK(back == sorted(added));
  if (coarse.size() * added.size() <= 2'000'000) {
    ReferenceDecoder ref(bytes, q, coarse, added.size());
    CHECK(ref.points == back);
  }
  return bytes;
}

// A decoded (possibly corrupted) layer must still be a valid set of added points.
void check_valid_output(const Points& out, std::uint64_t n, const Points& coarse, int q) {
  REQUIRE(out.size() == n);
  for (std::size_t i = 0; i < out.size(); ++i) {
    CHECK(((out[i][0] | out[i][1] | out[i][2]) >> q) == 0u);
    if (i) CHECK(out[i - 1] < out[i]);
    CHECK_FALSE(std::binary_search(coarse.begin(), coarse.end(), out[i]));
  }
}

}  // namespace

TEST_CASE("refinement round trips on random splits of the sample sets") {
  const int q = 12;
  const std::vector<std::pair<const char*, Points>> sets{
      {"torus", quantize(samples::torus(40, 24), q)},
      {"sphere", quantize(samples::uv_sphere(30, 40), q)},
      {"ball", quantize(samples::random_ball(3000, 7), q)},
      {"lattice", quantize(samples::lattice(12, 10, 8), q)},
      {"clustered", quantize(samples::clustered(6, 400, 3), q)},
      {"coplanar", quantize(samples::coplanar(1500, 5), q)},
  };
  for (const auto& set : sets)
    for (double fraction : {0.1, 0.3, 0.5, 0.9}) {
      const char* name = set.first;
      CAPTURE(name);
      CAPTURE(fraction);
      const Split s = split_random(set.second, fraction, 11);
      round_trip(s.coarse, s.added, q);
    }
}

TEST_CASE("refinement round trips on structured splits") {
  const int q = 12;
  const Points pts = quantize(samples::uv_sphere(40, 50), q);
  const std::uint32_t mid = pts[pts.size() / 2][0];
  SUBCASE("added far from coarse") {
    const Split s = split_by(pts, [&](std::size_t i) { return pts[i][0] > mid; });
    round_trip(s.coarse, s.added, q);
  }
  SUBCASE("added interleaved with coarse") {
    const Split s = split_by(pts, [](std::size_t i) { return i % 2 == 1; });
    round_trip(s.coarse, s.added, q);
  }
  SUBCASE("a single added point") {
    for (std::size_t at : {std::size_t{0}, pts.size() / 3, pts.size() - 1}) {
      const Split s = split_by(pts, [&](std::size_t i) { return i == at; });
      round_trip(s.coarse, s.added, q);
    }
  }
  SUBCASE("a single coarse point") {
    const Split s = split_by(pts, [](std::size_t i) { return i != 5; });
    round_trip(s.coarse, s.added, q);
  }
}

TEST_CASE("refinement round trips with every header choice") {
  const int q = 12;
  const Points pts = quantize(samples::torus(24, 16), q);
  const Split s = split_random(pts, 0.3, 4);
  for (int k : {0, 1, 2, 3, 4, 7, 15})
    for (int classes = 1; classes <= 4; ++classes) {
      CAPTURE(k);
      CAPTURE(classes);
      const RefinementParams p = params(k, classes);
      const auto bytes = round_trip(s.coarse, s.added, q, &p);
      CHECK((bytes[0] >> 4) == k);
      CHECK(((bytes[0] >> 2) & 3) + 1 == classes);
    }
}

TEST_CASE("refinement on the 2x2x2 grid: every split") {
  // q = 1: the root's children are the eight grid points.
  Points all;
  for (std::uint32_t i = 0; i < 8; ++i) all.push_back({i >> 2, (i >> 1) & 1u, i & 1u});
  int cases = 0;
  for (unsigned coarse_mask = 1; coarse_mask < 256; ++coarse_mask)
    for (unsigned added_mask = 1; added_mask < 256; ++added_mask) {
      if (coarse_mask & added_mask) continue;
      Points coarse, added;
      for (unsigned i = 0; i < 8; ++i) {
        if ((coarse_mask >> i) & 1u) coarse.push_back(all[i]);
        if ((added_mask >> i) & 1u) added.push_back(all[i]);
      }
      sort_canonical(coarse);
      round_trip(coarse, added, 1);
      ++cases;
    }
  CHECK(cases == 6050);  // 3^8 - 2 * 2^8 + 1 splits with both parts non-empty
}

TEST_CASE("refinement at q = 2 and q = 21") {
  std::mt19937_64 rng(5);
  SUBCASE("q = 2") {
    for (int trial = 0; trial < 200; ++trial) {
      Points coarse, added;
      for (std::uint32_t i = 0; i < 64; ++i) {
        const auto r = rng() % 3;
        const GridPoint p{i >> 4, (i >> 2) & 3u, i & 3u};
        if (r == 0) coarse.push_back(p);
        else if (r == 1) added.push_back(p);
      }
      if (coarse.empty() || added.empty()) continue;
      round_trip(coarse, added, 2);
    }
  }
  SUBCASE("q = 21, points at the corners and spread over the grid") {
    const std::uint32_t top = (1u << 21) - 1;
    std::set<GridPoint> set{{0, 0, 0}, {top, top, top}, {top, 0, top}, {0, top, 0}, {1, 0, 0}, {top - 1, top, top}};
    std::uniform_int_distribution<std::uint32_t> any(0, top);
    while (set.size() < 600) set.insert({any(rng), any(rng), any(rng)});
    const Points pts(set.begin(), set.end());
    const Split s = split_random(pts, 0.4, 9);
    round_trip(s.coarse, s.added, 21);
    const Split corners = split_by(pts, [](std::size_t i) { return i % 3 == 0; });
    round_trip(corners.coarse, corners.added, 21);
    const RefinementParams p = params(15, 4);
    round_trip(s.coarse, s.added, 21, &p);
  }
  SUBCASE("q = 21, a dense surface") {
    const Points pts = quantize(samples::uv_sphere(30, 30), 21);
    const Split s = split_random(pts, 0.3, 2);
    round_trip(s.coarse, s.added, 21);
  }
}

TEST_CASE("refinement streams do not depend on the order of the input") {
  const Points pts = quantize(samples::torus(30, 20), 12);
  const Split s = split_random(pts, 0.3, 3);
  const auto bytes = encode_refinement(s.coarse, s.added, 12);
  std::mt19937_64 rng(8);
  for (int i = 0; i < 5; ++i) {
    Points added = s.added, coarse = s.coarse;
    std::shuffle(added.begin(), added.end(), rng);
    std::shuffle(coarse.begin(), coarse.end(), rng);
    CHECK(encode_refinement(s.coarse, added, 12) == bytes);
    CHECK(encode_refinement(coarse, added, 12) == bytes);
  }
}

TEST_CASE("refinement is cheaper than coding the added points alone") {
  const Points pts = quantize(samples::uv_sphere(60, 80), 12);
  const Split s = split_by(pts, [](std::size_t i) { return i % 3 == 0; });
  const auto refined = encode_refinement(s.coarse, s.added, 12);
  const auto alone = encode_octree(s.added, 12);
  CHECK(refined.size() < alone.size());
}

TEST_CASE("refinement: an empty layer and invalid arguments") {
  const Points coarse{{1, 2, 3}, {4, 5, 6}};
  CHECK(encode_refinement(coarse, {}, 4).empty());
  CHECK(decode_refinement(nullptr, 0, 4, coarse, 0).empty());
  const std::uint8_t zero = 0;
  CHECK(status_of([&] { decode_refinement(&zero, 1, 4, coarse, 0); }) == Status::bad_layer);
  CHECK(status_of([&] { encode_refinement(coarse, {{1, 2, 3}}, 4); }) == Status::invalid_argument);
  CHECK(status_of([&] { encode_refinement(coarse, {{0, 0, 1}, {0, 0, 1}}, 4); }) == Status::invalid_argument);
  CHECK(status_of([&] { encode_refinement({}, {{0, 0, 1}}, 4); }) == Status::invalid_argument);
  CHECK(status_of([&] { encode_refinement(coarse, {{0, 0, 16}}, 4); }) == Status::invalid_argument);
  CHECK(status_of([&] { encode_refinement(coarse, {{0, 0, 1}}, 0); }) == Status::invalid_argument);
  CHECK(status_of([&] { encode_refinement(coarse, {{0, 0, 1}}, 22); }) == Status::invalid_argument);
  CHECK(status_of([&] { encode_refinement(coarse, {{0, 0, 1}}, 4, params(16, 1)); }) ==
        Status::invalid_argument);
  CHECK(status_of([&] { encode_refinement(coarse, {{0, 0, 1}}, 4, params(4, 5)); }) ==
        Status::invalid_argument);
  const std::uint8_t some[2] = {0x40, 0};
  CHECK(status_of([&] { decode_refinement(some, 2, 4, {}, 1); }) == Status::invalid_argument);
  CHECK(status_of([&] { decode_refinement(some, 2, 4, {{4, 5, 6}, {1, 2, 3}}, 1); }) == Status::invalid_argument);
}

TEST_CASE("refinement: hand-made streams") {
  const int q = 4;
  const Points coarse{{15, 15, 15}};  // last in Morton order
  SUBCASE("no table for a slot that is used") {
    BitWriter w;
    w.put(0, 4);  // K = 0
    w.put(0, 2);  // L = 1
    for (int d = 0; d < q; ++d) w.put(0, 1);
    const auto b = w.finish();
    CHECK(status_of([&] { decode_refinement(b.data(), b.size(), q, coarse, 1); }) == Status::bad_layer);
  }
  // One-symbol tables that fill every node: the stream claims 8^4 points.
  BitWriter w;
  w.put(0, 4);
  w.put(0, 2);
  for (int d = 0; d < q; ++d) {
    w.put(1, 1);    // a table follows
    w.put(1, 1);    // one-symbol form
    w.put(254, 8);  // the occupancy 255
  }
  const auto full = w.finish();
  SUBCASE("more points than declared") {
    CHECK(status_of([&] { decode_refinement(full.data(), full.size(), q, coarse, 100); }) == Status::bad_layer);
  }
  SUBCASE("an added point on a coarse point") {
    CHECK(status_of([&] { decode_refinement(full.data(), full.size(), q, coarse, 4096); }) == Status::bad_layer);
    const Points away{{0, 0, 0}};
    CHECK(status_of([&] { decode_refinement(full.data(), full.size(), q, away, 4096); }) == Status::bad_layer);
  }
  SUBCASE("a single symbol outside the alphabet") {
    BitWriter b;
    b.put(0, 4);
    b.put(0, 2);
    b.put(1, 1);
    b.put(1, 1);
    b.put(255, 8);
    for (int d = 1; d < q; ++d) b.put(0, 1);
    const auto bytes = b.finish();
    CHECK(status_of([&] { decode_refinement(bytes.data(), bytes.size(), q, coarse, 1); }) ==
          Status::bad_huffman_table);
  }
}

TEST_CASE("malformed refinement streams are rejected, never misread") {
  const int q = 10;
  const Points pts = quantize(samples::random_sphere_points(900, 4), q);
  const Split s = split_random(pts, 0.3, 6);
  const auto good = encode_refinement(s.coarse, s.added, q);
  const std::uint64_t n = s.added.size();
  REQUIRE(good.size() > 16);
  const auto decode = [&](const std::vector<std::uint8_t>& b, std::uint64_t count) {
    return decode_refinement(b.data(), b.size(), q, s.coarse, count);
  };
  const auto is_stream_error = [](Status st) { return st == Status::bad_layer || st == Status::bad_huffman_table; };

  SUBCASE("truncated") {
    for (std::size_t len = 0; len < good.size(); ++len) {
      const std::vector<std::uint8_t> cut(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(len));
      CAPTURE(len);
      CHECK(is_stream_error(status_of([&] { decode(cut, n); })));
    }
  }
  SUBCASE("extra bytes") {
    for (int extra : {0x00, 0x80, 0xff}) {
      auto longer = good;
      longer.push_back(static_cast<std::uint8_t>(extra));
      CHECK(status_of([&] { decode(longer, n); }) == Status::bad_layer);
    }
  }
  SUBCASE("wrong point count") {
    for (std::uint64_t wrong : {n - 1, n + 1, 2 * n, std::uint64_t{1} << 40})
      CHECK(status_of([&] { decode(good, wrong); }) == Status::bad_layer);
  }
  SUBCASE("bit flips and garbage") {
    std::mt19937_64 rng(12);
    int errors = 0, decoded = 0;
    for (int trial = 0; trial < 400; ++trial) {
      auto bad = good;
      const int flips = trial < 250 ? 1 : 1 + static_cast<int>(rng() % 8);
      for (int f = 0; f < flips; ++f) bad[rng() % bad.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      if (trial >= 350)  // a run of random bytes
        for (std::size_t i = rng() % bad.size(), e = std::min(bad.size(), i + 1 + rng() % 16); i < e; ++i)
          bad[i] = static_cast<std::uint8_t>(rng());
      try {
        check_valid_output(decode(bad, n), n, s.coarse, q);
        ++decoded;
      } catch (const StreamError& e) {
        CHECK(is_stream_error(e.error().status));
        ++errors;
      }
    }
    CHECK(errors >= 100);  // equal-length codewords swapped keep the stream in sync: still a valid set
    MESSAGE(errors << " rejected, " << decoded << " decoded to another valid set");
  }
}

// Whether a BASE payload, its coder byte replaced by `coder`, decodes to
// `points` (false when it fails).
bool decodes_as(std::vector<std::uint8_t> base, std::uint8_t coder, int q, const Points& points) {
  base[0] = coder;
  try {
    return decode_base(base.data(), base.size(), q, points.size()) == points;
  } catch (const StreamError&) {
    return false;
  }
}

TEST_CASE("base layer on two threads: the same stream and the same points") {
  // With a helper free, the encoder ranks half of each depth of 4,096 nodes
  // or more on it, and the decoder searches the nearest nodes of each depth
  // of 2,048 or more there, ahead of its decoding (pointset/octree.cpp).
  // A 9,600-point sphere has such depths.
  Points sphere = quantize(samples::uv_sphere(80, 120), 12);
  sort_canonical(sphere);
  sphere.erase(std::unique(sphere.begin(), sphere.end()), sphere.end());
  REQUIRE(sphere.size() > 8192);
  HelperBudget two(2);
  const auto one = encode_base(sphere, 12);
  REQUIRE(one[0] == 5);  // ranked
  CHECK(encode_base(sphere, 12, BaseCoder::ranked, &two) == one);
  CHECK(decode_base(one.data(), one.size(), 12, sphere.size(), TableForm::deltas, &two) == sphere);
}

TEST_CASE("base layer: the ranked octree (coder 5) codes surfaces smaller and decodes every set exactly") {
  // A sampled surface: the plane through the neighbouring node centres
  // predicts the children, so the ranked coder is chosen and is smaller.
  const Points sphere = quantize(samples::uv_sphere(80, 120), 12);
  const auto base = encode_base(sphere, 12);
  REQUIRE(!base.empty());
  CHECK(base[0] == 5);
  const auto plain = encode_octree(sphere, 12);
  CHECK(base.size() < plain.size() + 1);
  Points sorted = sphere;
  sort_canonical(sorted);
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  CHECK(decode_base(base.data(), base.size(), 12, sorted.size()) == sorted);
  // Whatever coder the encoder picks, the set comes back, at any q.
  for (int q : {1, 3, 8, 12, 21}) {
    CAPTURE(q);
    for (const auto& m : {samples::random_ball(500, 3), samples::lattice(6, 5, 4), samples::torus(30, 12)}) {
      Points p = quantize(m, q);
      sort_canonical(p);
      p.erase(std::unique(p.begin(), p.end()), p.end());
      for (const BaseCoder coder : {BaseCoder::octree, BaseCoder::ranked}) {
        const auto b = encode_base(p, q, coder);
        CHECK((b[0] == 0 || b[0] == static_cast<std::uint8_t>(coder)));
        CHECK(decode_base(b.data(), b.size(), q, p.size()) == p);
      }
    }
  }
  // A single point gains nothing from ranking: coder 0.
  const Points one{{5, 6, 7}};
  CHECK(encode_base(one, 4)[0] == 0);
  // Unknown coders (1-4 were removed in spec 0.25), empty payload, a wrong
  // count. A coder-5 stream relabelled as a removed coder is refused.
  for (const int coder : {1, 2, 3, 4, 6, 255}) {
    CAPTURE(coder);
    const std::uint8_t unknown[] = {static_cast<std::uint8_t>(coder), 0};
    CHECK(status_of([&] { decode_base(unknown, 2, 4, 1); }) == Status::bad_layer);
    CHECK_FALSE(decodes_as(base, static_cast<std::uint8_t>(coder), 12, sorted));
  }
  const std::uint8_t four[] = {4, 0};
  CHECK(status_of([&] { decode_base(four, 0, 4, 1); }) == Status::bad_layer);
  CHECK(status_of([&] { encode_base(sphere, 12, static_cast<BaseCoder>(1)); }) == Status::invalid_argument);
  CHECK(status_of([&] { decode_base(base.data(), base.size(), 12, sorted.size() - 1); }) == Status::bad_layer);
  CHECK(status_of([&] { decode_base(base.data(), base.size() - 1, 12, sorted.size()); }) == Status::bad_layer);
}

// A ranked depth's header fields in a BASE payload of coder 5 (spec 8.2):
// whether it is ranked, its weight, its quadric flag and how many of its
// tables are paired.
struct RankedDepth {
  bool ranked = false;
  int gap = 0;
  bool quadric = false;
  int paired = 0;
};
std::vector<RankedDepth> ranked_depths(const std::vector<std::uint8_t>& base, int q) {
  REQUIRE(base[0] == 5);
  BitReader in(base.data() + 1, base.size() - 1, "test");
  in.get(4);
  const int classes = static_cast<int>(in.get(2)) + 1;
  std::vector<RankedDepth> out(static_cast<std::size_t>(q));
  for (auto& d : out) {
    d.ranked = in.get(1) == 1;
    if (d.ranked) d.gap = static_cast<int>(in.get(5));
    if (d.ranked) d.quadric = in.get(1) == 1;
    for (int j = 0; j < (d.ranked ? classes : 1); ++j)
      d.paired += TableCode::read(in, d.ranked ? 255 : 256, true, "test", TableForm::deltas).paired();
  }
  return out;
}

// The candidates, in their order, that lie at least r from every one kept
// before them: points spaced about evenly, as a scan spaces them.
Points evenly_spread(const Points& candidates, std::int64_t r) {
  Points even;
  const auto side = static_cast<std::uint32_t>(r);  // buckets of side r: the spacing test stays local
  std::map<std::array<std::uint32_t, 3>, std::vector<GridPoint>> grid;
  for (const GridPoint& c : candidates) {
    const std::array<std::uint32_t, 3> cell{c[0] / side, c[1] / side, c[2] / side};
    bool near = false;
    for (int dx = -1; dx <= 1 && !near; ++dx)
      for (int dy = -1; dy <= 1 && !near; ++dy)
        for (int dz = -1; dz <= 1 && !near; ++dz) {
          const auto it = grid.find({cell[0] + dx, cell[1] + dy, cell[2] + dz});
          if (it == grid.end()) continue;
          for (const GridPoint& p : it->second) {
            std::int64_t d2 = 0;
            for (std::size_t a = 0; a < 3; ++a) d2 += (std::int64_t{p[a]} - c[a]) * (std::int64_t{p[a]} - c[a]);
            near = near || d2 < r * r;
          }
        }
    if (!near) grid[cell].push_back(c), even.push_back(c);
  }
  return even;
}

TEST_CASE("base layer: coder 5 ranks by the children of the nodes decoded before, and by a quadric where it pays") {
  // On sampled curved surfaces the occupied children of the neighbouring
  // nodes already decoded locate the sheet twice as finely as their centres,
  // and the quadric through them follows the curve: coder 5 chooses it at
  // some depth, the plane at others.
  for (const auto& mesh : {samples::torus(160, 60, 1.0, 0.2), samples::uv_sphere(80, 120)}) {
    const Points pts = quantize(mesh, 12);
    Points sorted = pts;
    sort_canonical(sorted);
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    const auto three = encode_base(pts, 12), plain = encode_base(pts, 12, BaseCoder::octree);
    REQUIRE(three[0] == 5);
    MESSAGE(sorted.size() << " points: coder 0 " << plain.size() << " bytes, coder 5 " << three.size());
    CHECK(100 * three.size() < 90 * plain.size());
    CHECK(decode_base(three.data(), three.size(), 12, sorted.size()) == sorted);
    const auto depths = ranked_depths(three, 12);
    CHECK(std::any_of(depths.begin(), depths.end(), [](const RankedDepth& d) { return d.quadric; }));
    CHECK(std::any_of(depths.begin(), depths.end(), [](const RankedDepth& d) { return d.ranked && !d.quadric; }));
  }
  // A depth of more than 16,384 nodes is first judged on a sample block of
  // its nodes (their causal points taken from the block's own slice of the
  // occupancies): on 50,000 evenly spaced points of a sphere the last depth
  // (one point per node) pays and must be ranked. (The bunny's last depth
  // pays only with the weights or the quadric, which the sample now tries;
  // these synthetic points pay with the plane alone too.)
  {
    const Points big = sorted(evenly_spread(quantize(samples::random_sphere_points(100000, 9), 12), 19));
    REQUIRE(big.size() > 40000);
    const auto b = encode_base(big, 12);
    const auto depths = ranked_depths(b, 12);
    MESSAGE(big.size() << " evenly spread points: " << b.size() << " bytes");
    CHECK(depths[11].ranked);
  }
  // The points of a node are capped at 32: with 15 neighbours on a dense
  // lattice (up to 8 children each) the lists are cut, and the set still
  // comes back; the same at q = 21 with points at the grid's far corners
  // (the bounds of spec 8.2).
  Points lattice;
  for (std::uint32_t x = 0; x < 9; ++x)
    for (std::uint32_t y = 0; y < 9; ++y)
      for (std::uint32_t z = 0; z < 9; ++z) lattice.push_back({x, y, z});
  const std::uint32_t far = (1u << 21) - 1;
  for (const GridPoint& c : Points{{far, far, far}, {far, far - 1, far}, {far, 0, 0}, {far - 1, 1, 0}, {0, far, 1}})
    lattice.push_back(c);
  for (int q : {6, 21}) {
    Points p;
    for (const GridPoint& g : lattice)
      if (((g[0] | g[1] | g[2]) >> q) == 0) p.push_back(g);
    p = sorted(p);
    const auto b = encode_base(p, q);
    CHECK(b[0] == 5);
    CHECK(decode_base(b.data(), b.size(), q, p.size()) == p);
  }
}

TEST_CASE("base layer: coder 5 pairs the tables where that is smaller, and a ranked depth's pairs cost a bit") {
  // A sphere sampled evenly: deep depths where most nodes have one child,
  // the ranking's first most often.
  const Points pts = sorted(evenly_spread(quantize(samples::random_sphere_points(60000, 13), 12), 24));
  const auto four = encode_base(pts, 12);
  REQUIRE(four[0] == 5);
  CHECK(decode_base(four.data(), four.size(), 12, pts.size()) == pts);
  const auto d4 = ranked_depths(four, 12);
  int paired = 0;
  for (const RankedDepth& d : d4) paired += d.paired;
  CHECK(paired > 0);
  // A ranked depth whose paired table's pair code is the one-symbol form:
  // pairs would cost nothing, so the stream is refused before any node.
  BitWriter w;
  w.put(1, 4);  // neighbours
  w.put(0, 2);  // one context
  w.put(1, 1);  // depth 0 ranked
  w.put(0, 5);  // gap weight
  w.put(0, 1);  // no quadric
  w.put(1, 1);  // paired
  w.put(1, 1);  // pair code: one symbol,
  w.put(0, 7);  // the pair (0, 0)
  std::vector<std::uint8_t> bad{5};
  const auto bits = w.finish();
  bad.insert(bad.end(), bits.begin(), bits.end());
  CHECK(status_of([&] { decode_base(bad.data(), bad.size(), 1, 1); }) == Status::bad_layer);
}

TEST_CASE("base layer: coder 5 ranks the children of a volume's interior farthest from the points around them") {
  // Points kept at least r apart filling a ball, as a tetrahedral mesh
  // spaces its interior: no plane passes through them, and at the depths of
  // one point per node the occupied child is the one far from the points
  // known around it. Coder 5's weight 16 pays there.
  const Points even = sorted(evenly_spread(quantize(samples::random_ball(20000, 17), 12), 150));
  REQUIRE(even.size() > 2000);
  const auto five = encode_base(even, 12);
  REQUIRE(five[0] == 5);
  CHECK(decode_base(five.data(), five.size(), 12, even.size()) == even);
  const auto depths = ranked_depths(five, 12);
  CHECK(std::any_of(depths.begin(), depths.end(), [](const RankedDepth& d) { return d.gap == 16; }));
  // On a sampled surface the plane and the quadric rank better: no depth
  // takes weight 16 there.
  const Points sphere = quantize(samples::uv_sphere(80, 120), 12);
  const auto surface = encode_base(sphere, 12);
  REQUIRE(surface[0] == 5);
  const auto on_surface = ranked_depths(surface, 12);
  CHECK(std::none_of(on_surface.begin(), on_surface.end(), [](const RankedDepth& d) { return d.gap == 16; }));
  // Weight 16 ranks by g alone, farthest first: node (0,0,0) at depth 1 of
  // q = 3 (centre 4,4,4; children's centres 2 or 6 per axis) and points
  // (1,1,1) and (1,3,7) beside children 0 and 1: child 6, (6,6,2), is the
  // farthest from both (g = 51; the next, 7, g = 35), and weight 0 (the
  // plane through the three points) orders the children otherwise.
  const Doubled nb[3] = {{4, 4, 4}, {1, 1, 1}, {1, 3, 7}};
  std::array<int, 8> far{}, plain{};
  ChildKeys(GridPoint{0, 0, 0}, 1, 3, nb, 3, true, 1).order(0u, kFarRanking, far);
  ChildKeys(GridPoint{0, 0, 0}, 1, 3, nb, 3, true, 1).order(0u, 0, plain);
  CHECK(far[0] == 6);
  CHECK(far[1] == 7);
  CHECK(far != plain);
  // Weights above 16 are refused before any table is read.
  for (const std::uint32_t weight : {17u, 31u}) {
    CAPTURE(weight);
    BitWriter w;
    w.put(1, 4);       // neighbours
    w.put(0, 2);       // one context
    w.put(1, 1);       // depth 0 ranked
    w.put(weight, 5);  // its weight
    w.put(0, 1);       // no quadric
    w.put(0, 1);       // a plain table: lengths 1, 1 (symbols 0 and 1)
    std::vector<std::uint8_t> bad{5};
    const auto bits = w.finish();
    bad.insert(bad.end(), bits.begin(), bits.end());
    CHECK(status_of([&] { decode_base(bad.data(), bad.size(), 1, 1); }) == Status::bad_layer);
  }
}

TEST_CASE("base layer: gap weights win on evenly spread points, and the node itself is not a gap") {
  // Points kept at least r apart on a sphere, as a scan spaces them: at the
  // depths of one or two points per node, the occupied children lie far from
  // the neighbouring nodes' centres, and weights above 0 make the symbols
  // cheaper.
  Points even = evenly_spread(quantize(samples::random_sphere_points(30000, 7), 12), 40);
  sort_canonical(even);
  REQUIRE(even.size() > 2000);
  const auto base = encode_base(even, 12);
  CHECK(base[0] == 5);
  CHECK(decode_base(base.data(), base.size(), 12, even.size()) == even);
  const auto depths = ranked_depths(base, 12);
  CHECK(std::any_of(depths.begin(), depths.end(), [](const RankedDepth& d) { return d.gap > 0; }));
  // The weights rank by distance to the neighbours other than the node
  // itself: with the node's own centre (distance 0 from no child, and the
  // same from all eight) the gap term could not tell children apart.
  // The node (centre 4,4,4) first, then three nodes beside it on the plane
  // z = 4: children (2,2,z) are the farthest from those three.
  const Doubled nb[4] = {{4, 4, 4}, {12, 4, 4}, {12, 8, 4}, {4, 12, 4}};
  std::array<int, 8> plain{}, skip{}, all{};
  ChildKeys(GridPoint{0, 0, 0}, 1, 3, nb, 4, false).order(0u, 0, plain);
  ChildKeys(GridPoint{0, 0, 0}, 1, 3, nb, 4, true, 1).order(0u, 15, skip);
  ChildKeys(GridPoint{0, 0, 0}, 1, 3, nb, 4, true, 0).order(0u, 15, all);
  CHECK((plain[0] == 6 || plain[0] == 7));  // nearest the neighbours' centroid
  CHECK((skip[0] == 0 || skip[0] == 1));
  CHECK(all == plain);  // every child is equally far from the node's own centre
}

// ChildKeys packs each child's ranking key (spec 8A.1 step 5, 8A.1's kappa,
// 8.2's gap skipping the node itself) into one integer; order() and
// symbol() must rank exactly as the keys compared one by one, up to the
// largest magnitudes inputs reach (q = 21, 32 points, weight 15); so must
// the far ranking (spec 8A.1, weight kFarRanking) by (mask, -g, t, e, c).
TEST_CASE("ChildKeys ranks as the spec's keys, at the largest magnitudes too") {
  __extension__ typedef __int128 I128;
  // Spec 8A.1 "Reduction to B bits".
  const auto reduce = [](std::vector<std::int64_t> v, int bits) {
    std::uint64_t m = 0;
    for (auto x : v) m = std::max<std::uint64_t>(m, static_cast<std::uint64_t>(x < 0 ? -x : x));
    int len = 0;
    while (len < 64 && (m >> len) != 0) ++len;
    const int sh = std::max(0, len - bits);
    for (auto& x : v) x = x < 0 ? -((-x) >> sh) : x >> sh;
    return v;
  };
  std::mt19937_64 rng(11);
  int cases = 0, gapped_cases = 0, far_decided = 0;
  I128 lowest = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    // Every seventh node at the origin with its neighbours far away: gap
    // terms beyond 2^100, about the largest any input reaches (32
    // neighbours, weight 15; the spec bounds them by 2^104).
    const bool far = trial % 7 == 0;
    const int q = trial % 3 == 0 || far ? 21 : 1 + static_cast<int>(rng() % 21);
    const int d = far ? q - 1 : static_cast<int>(rng() % static_cast<std::uint64_t>(q));
    const std::int64_t h = std::int64_t{1} << (q - d);
    const std::uint32_t cells = 1u << d;
    const GridPoint node = far ? GridPoint{0, 0, 0}
                               : GridPoint{static_cast<std::uint32_t>(rng() % cells),
                                           static_cast<std::uint32_t>(rng() % cells),
                                           static_cast<std::uint32_t>(rng() % cells)};
    const int k = far ? kMaxRankPoints : 1 + static_cast<int>(rng() % kMaxRankPoints);
    const int gap_from = static_cast<int>(rng() % 2);
    const int gap = far ? 15 : static_cast<int>(rng() % 16);
    std::vector<Doubled> nb(static_cast<std::size_t>(k));
    const std::uint64_t span = std::uint64_t{2} << q;  // doubled coordinates below 2^(q+1)
    for (auto& x : nb) {
      for (std::size_t a = 0; a < 3; ++a)
        x[a] = static_cast<std::int32_t>(trial % 5 == 0 ? (rng() % 2) * (span - 1) : rng() % span);
      if (far) {  // at the far corner, on the plane x = y, which passes through the node
        const std::uint64_t u = rng() % 256, w = rng() % 256;
        x = {static_cast<std::int32_t>(span - 1 - u), static_cast<std::int32_t>(span - 1 - u),
             static_cast<std::int32_t>(span - 1 - w)};
      }
    }
    const unsigned mask = trial % 4 == 0 ? static_cast<unsigned>(rng() % 256) : 0u;
    const ChildKeys keys(node, d, q, nb.data(), k, true, gap_from);
    // The spec's keys, computed plainly.
    std::int64_t s[3] = {0, 0, 0};
    for (const auto& x : nb)
      for (std::size_t a = 0; a < 3; ++a) s[a] += x[a];
    std::vector<std::int64_t> m(6, 0);
    const int pairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    for (int e = 0; e < 6; ++e) {
      std::int64_t sum = 0;
      const auto a = static_cast<std::size_t>(pairs[e][0]), b = static_cast<std::size_t>(pairs[e][1]);
      for (const auto& x : nb) sum += std::int64_t{x[a]} * x[b];
      m[static_cast<std::size_t>(e)] = k * sum - s[pairs[e][0]] * s[pairs[e][1]];
    }
    m = reduce(m, 31);
    const std::int64_t xx = m[0], yy = m[1], zz = m[2], xy = m[3], xz = m[4], yz = m[5];
    const std::int64_t dg[3] = {yy * zz - yz * yz, xx * zz - xz * xz, xx * yy - xy * xy};
    const std::int64_t axy = xz * yz - xy * zz, axz = xy * yz - xz * yy, ayz = xy * xz - xx * yz;
    const int j = dg[1] > dg[0] ? (dg[2] > dg[1] ? 2 : 1) : (dg[2] > dg[0] ? 2 : 0);
    std::vector<std::int64_t> n = j == 0 ? std::vector<std::int64_t>{dg[0], axy, axz}
                                  : j == 1 ? std::vector<std::int64_t>{axy, dg[1], ayz}
                                           : std::vector<std::int64_t>{axz, ayz, dg[2]};
    n = reduce(n, 20);
    const std::int64_t n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    const bool gapped = gap > 0 && n2 > 0 && gap_from < k;
    gapped_cases += gapped;
    std::array<std::tuple<int, I128, std::int64_t, std::int64_t, int>, 8> key, far_key;
    for (int c = 0; c < 8; ++c) {
      std::int64_t u[3], t = 0, e = 0, g = INT64_MAX;
      for (std::size_t a = 0; a < 3; ++a) {
        u[a] = (2 * std::int64_t{node[a]} + ((c >> (2 - a)) & 1)) * h + h / 2;
        const std::int64_t v = k * u[a] - s[a];
        t += n[a] * v;
        e += v * v;
      }
      for (int i = gap_from; i < k; ++i) {
        std::int64_t d2 = 0;
        for (std::size_t a = 0; a < 3; ++a) {
          const std::int64_t w = u[a] - nb[static_cast<std::size_t>(i)][a];
          d2 += w * w;
        }
        g = std::min(g, d2);
      }
      t = t < 0 ? -t : t;
      const I128 kappa = gapped ? 32 * I128{t} * t - I128{gap} * k * k * n2 * g : 0;
      key[static_cast<std::size_t>(c)] = {(mask >> c) & 1u ? 0 : 1, kappa, t, e, c};
      far_key[static_cast<std::size_t>(c)] = {(mask >> c) & 1u ? 0 : 1, gap_from < k ? -I128{g} : 0, t, e, c};
      if (kappa < lowest) lowest = kappa;
    }
    std::array<int, 8> want{}, got{};
    std::iota(want.begin(), want.end(), 0);
    std::sort(want.begin(), want.end(),
              [&](int a, int b) { return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)]; });
    keys.order(mask, gap, got);
    INFO("trial " << trial << ", q " << q << ", d " << d << ", k " << k << ", gap " << gap);
    CHECK(got == want);
    const unsigned occupancy = 1u + static_cast<unsigned>(rng() % 255);
    CHECK(keys.symbol(mask, gap, occupancy) == ranked_symbol(want, occupancy));
    std::iota(want.begin(), want.end(), 0);
    std::sort(want.begin(), want.end(), [&](int a, int b) {
      return far_key[static_cast<std::size_t>(a)] < far_key[static_cast<std::size_t>(b)];
    });
    keys.order(mask, kFarRanking, got);
    CHECK(got == want);
    CHECK(keys.symbol(mask, kFarRanking, occupancy) == ranked_symbol(want, occupancy));
    far_decided += want != std::array<int, 8>{0, 1, 2, 3, 4, 5, 6, 7} && std::get<1>(far_key[0]) != 0;
    // symbols(): for a list of weights in any order, with repeats (its
    // gapped keys step from each weight to the next), the symbols of the
    // orders that keys() gives weight by weight; all children or none in
    // the mask too (where it leaves the uniform lift out).
    std::vector<int> weights{gap, kFarRanking, gap};
    for (int i = 0; i < 9; ++i) weights.push_back(static_cast<int>(rng() % (kFarRanking + 1)));
    std::vector<std::uint8_t> batch(weights.size());
    for (const unsigned list_mask : {mask, 0u, 0xFFu}) {
      keys.symbols(list_mask, weights.data(), weights.size(), occupancy, batch.data());
      for (std::size_t w = 0; w < weights.size(); ++w) {
        keys.order(list_mask, weights[w], got);
        CHECK(batch[w] == ranked_symbol(got, occupancy));
      }
    }
    ++cases;
  }
  CHECK(cases == 3000);
  CHECK(gapped_cases > 1000);  // the gap term decides many of them
  CHECK(far_decided > 1000);   // and the far ranking reorders most
  CHECK(lowest < -(I128{1} << 100));  // near the largest magnitudes any input reaches
}

// The sorting and Morton helpers every layer decoder ends with.
TEST_CASE("radix_sort, morton_point and sort_canonical agree with the plain definitions") {
  std::mt19937_64 rng(5);
  for (int bits : {0, 1, 7, 13, 24, 36, 47, 63, 64}) {
    for (std::size_t n : {std::size_t{0}, std::size_t{5}, std::size_t{255}, std::size_t{256}, std::size_t{5000}}) {
      INFO("bits " << bits << ", n " << n);
      std::vector<std::uint64_t> keys(n);
      const std::uint64_t mask = bits == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
      for (auto& k : keys) k = rng() & mask;
      if (n > 10) keys[3] = keys[7];  // a repeated key
      auto want = keys;
      std::sort(want.begin(), want.end());
      radix_sort(keys, bits);
      CHECK(keys == want);
    }
  }
  for (int q : {1, 2, 3, 4, 12, 20, 21}) {
    INFO("q " << q);
    std::uniform_int_distribution<std::uint32_t> u(0, (1u << q) - 1);
    Points points;
    for (int i = 0; i < 3000; ++i) {
      const GridPoint p{u(rng), u(rng), u(rng)};
      CHECK(morton_point(morton_key(p, q), q) == p);
      points.push_back(p);
    }
    auto want = points;
    std::sort(want.begin(), want.end());  // std::array: x, then y, then z
    sort_canonical(points);
    CHECK(points == want);
  }
}

TEST_CASE("plane contexts (coder 7) round trip, and the encoder keeps the smaller coder") {
  const int q = 12;
  const Points pts = quantize(samples::torus(40, 24), q);
  const Split s = split_random(pts, 0.3, 5);
  for (int k : {0, 1, 4, 15})
    for (int classes = 1; classes <= 4; ++classes) {
      CAPTURE(k);
      CAPTURE(classes);
      RefinementParams p = params(k, classes);
      p.plane_contexts = true;
      // Read as coder 0 (the short header), the slot flags and tables no longer line up.
      check_coders(encode_refinement(s.coarse, s.added, q, p), s, q, RefineCoder::ranked_octree, RefineCoder::conditional_octree);
    }
  const RefinementLayer layer = encode_refinement_layer(s.coarse, s.added, q);
  REQUIRE((layer.coder == 0 || layer.coder == 7));
  const auto plain = encode_refinement(s.coarse, s.added, q);
  CHECK(layer.bytes.size() <= plain.size());
  if (layer.coder == 0) CHECK(layer.bytes == plain);
  CHECK(decode_refinement(layer.bytes.data(), layer.bytes.size(), q, s.coarse, s.added.size(), TableForm::deltas,
                          static_cast<RefineCoder>(layer.coder)) == sorted(s.added));
}

TEST_CASE("gap ranking: children far from every neighbour move up among those equally near the plane") {
  // q = 2, the root (h = 4): child centres at doubled coordinates 2 or 6.
  // Four neighbours on the plane z = 2 (doubled), one of them at the centre
  // of child 0; the four children with bz = 0 lie on the plane (t = 0).
  const Doubled nb[4] = {{0, 0, 2}, {0, 6, 2}, {6, 0, 2}, {2, 2, 2}};
  std::array<int, 8> plain{}, gapped{}, masked{};
  rank_children({0, 0, 0}, 0, 2, nb, 4, 0, plain);
  rank_children({0, 0, 0}, 0, 2, nb, 4, 0, gapped, nullptr, 1);
  rank_children({0, 0, 0}, 0, 2, nb, 4, 1u << 2, masked, nullptr, 15);
  // Plain: on the plane first, nearest the centroid (2, 2, 2) first.
  CHECK(plain[0] == 0);
  // Gap: child 6, centre (6, 6, 2), lies at squared distance 32 from its
  // nearest neighbour, children 2 and 4 at 4, child 0 at 0.
  CHECK(gapped[0] == 6);
  CHECK(gapped[3] == 0);
  for (int r = 0; r < 4; ++r) CHECK((gapped[static_cast<std::size_t>(r)] & 1) == 0);  // the plane still leads
  // Children holding coarse points still come first.
  CHECK(masked[0] == 2);
  CHECK(masked[1] == 6);
}

namespace {

// Points of `candidates` spread evenly (each kept unless a kept one lies
// within r grid units: a scan's spacing), and as added points an independent
// set of their 6-nearest-neighbour graph, taken greedily in random order up
// to a quarter, as a level of the hierarchy removes: every neighbour of an
// added point is coarse, so added points lie in the coarse level's gaps.
Split level_split(const Points& candidates, std::int64_t r) {
  const auto dist2 = [](const GridPoint& a, const GridPoint& b) {
    std::int64_t d2 = 0;
    for (std::size_t i = 0; i < 3; ++i) d2 += (std::int64_t{a[i]} - b[i]) * (std::int64_t{a[i]} - b[i]);
    return d2;
  };
  Points pts;
  for (const GridPoint& c : candidates)
    if (std::none_of(pts.begin(), pts.end(), [&](const GridPoint& p) { return dist2(p, c) < r * r; }))
      pts.push_back(c);
  std::vector<std::vector<std::size_t>> near(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    std::vector<std::size_t> others;
    for (std::size_t j = 0; j < pts.size(); ++j)
      if (j != i) others.push_back(j);
    std::partial_sort(others.begin(), others.begin() + 6, others.end(), [&](std::size_t x, std::size_t y) {
      return dist2(pts[i], pts[x]) < dist2(pts[i], pts[y]);
    });
    near[i].assign(others.begin(), others.begin() + 6);
  }
  std::vector<std::size_t> order(pts.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::shuffle(order.begin(), order.end(), std::mt19937_64(31));
  std::vector<char> added(pts.size(), 0), blocked(pts.size(), 0);
  std::size_t count = 0;
  for (std::size_t i : order) {
    if (blocked[i] || 4 * count >= pts.size()) continue;
    added[i] = 1, ++count;
    for (std::size_t j = 0; j < pts.size(); ++j)  // i's neighbours, and the points that list i
      if (std::find(near[i].begin(), near[i].end(), j) != near[i].end() ||
          std::find(near[j].begin(), near[j].end(), i) != near[j].end())
        blocked[j] = 1;
  }
  const Split s = split_by(pts, [&](std::size_t i) { return added[i] != 0; });
  REQUIRE(s.added.size() > pts.size() / 6);
  return s;
}

// The smallest layer that coders 0, 2 and 3 give with the encoder's 4
// neighbours and one of the gap weights `gaps` (0: no gap term), over the
// other header choices.
std::size_t smallest_layer(const Split& s, int q, const std::vector<int>& gaps) {
  std::size_t least = SIZE_MAX;
  for (bool planes : {false, true})
    for (int classes = 1; classes <= 4; ++classes)
      for (int gap : gaps) {
        RefinementParams p = params(4, classes);
        p.plane_contexts = planes;
        p.gap = gap;
        least = std::min(least, encode_refinement(s.coarse, s.added, q, p).size());
      }
  return least;
}

}  // namespace

TEST_CASE("gap ranking (coder 7) round trips, and wins where added points fill the coarse level's gaps") {
  const int q = 12;
  const Split s = level_split(quantize(samples::random_sphere_points(12000, 29), q), 90);  // about 1,700 points
  for (int k : {0, 1, 4, 15})
    for (int gap : {1, 7, 15})
      for (bool planes : {false, true}) {
        CAPTURE(k);
        CAPTURE(gap);
        CAPTURE(planes);
        RefinementParams p = params(k, 2);
        p.plane_contexts = planes;
        p.gap = gap;
        // Read as coder 0, the header's planes and gap fields become slot flags.
        check_coders(encode_refinement(s.coarse, s.added, q, p), s, q, RefineCoder::ranked_octree, RefineCoder::conditional_octree);
      }
  // The best gap ranking is at least 2 % smaller than the best ranking
  // without the gap term (4 neighbours); the encoder's choice, with a gap
  // ranking (coder 7), is no larger.
  const RefinementLayer layer = encode_refinement_layer(s.coarse, s.added, q);
  CHECK(layer.coder == 7);
  const std::size_t without = smallest_layer(s, q, {0}), gapped = smallest_layer(s, q, {1, 2, 3, 4, 6, 8, 12});
  CAPTURE(without);
  CAPTURE(gapped);
  CAPTURE(layer.bytes.size());
  MESSAGE("gap ranking: ", gapped, " bytes, without: ", without, " (", s.added.size(), " added points)");
  CHECK(50 * gapped <= 49 * without);
  CHECK(layer.bytes.size() <= gapped);
  CHECK(decode_refinement(layer.bytes.data(), layer.bytes.size(), q, s.coarse, s.added.size(), TableForm::deltas,
                          static_cast<RefineCoder>(layer.coder)) == sorted(s.added));

  // A weight per depth. Equal weights rank as one weight does; other
  // weights give other symbols; every choice decodes.
  const auto depth_coded = [&](const std::vector<int>& gaps, bool planes) {
    RefinementParams p = params(4, 3);
    p.plane_contexts = planes;
    p.depth_gaps = gaps;
    return encode_refinement(s.coarse, s.added, q, p);
  };
  const std::vector<std::vector<int>> choices{
      {0, 0, 0, 0, 0, 0, 2, 6, 8, 4, 2, 1},
      {15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4},
      {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}};
  std::set<std::vector<std::uint8_t>> distinct;
  for (const auto& gaps : choices)
    for (bool planes : {false, true}) {
      CAPTURE(planes);
      const auto bytes = depth_coded(gaps, planes);
      distinct.insert(bytes);
      // Read as coder 0, the weights become slot flags.
      check_coders(bytes, s, q, RefineCoder::ranked_octree, RefineCoder::conditional_octree);
    }
  CHECK(distinct.size() == 2 * choices.size());
  // The same weight at every depth is written as one weight: the same
  // bytes as its single weight.
  RefinementParams three = params(4, 3);
  three.gap = 6;
  RefinementParams four = params(4, 3);
  four.depth_gaps.assign(q, 6);
  CHECK(encode_refinement(s.coarse, s.added, q, four) == encode_refinement(s.coarse, s.added, q, three));
}

TEST_CASE("the ranked base coder's lattice neighbour search equals a k-d tree's, ties included") {
  // Cells of one depth, as the base coder sees them: Morton keys ascending,
  // an index being the position. Dense sheets and regular lattices (many
  // equal distances), a dense ball, sparse scatter, and a crowded cluster
  // among scattered cells; searched cell by cell and in buckets of 2 to 32
  // cells (where the search may hand over, never answer wrongly).
  std::mt19937_64 rng(17);
  auto make = [&](int d, int kind) {
    const std::uint32_t side = 1u << d;
    std::set<std::uint64_t> keys;
    std::uniform_int_distribution<std::uint32_t> any(0, side - 1);
    for (int i = 0; i < 3000; ++i) {
      GridPoint c{any(rng), any(rng), any(rng)};
      const std::uint32_t w = std::min(side, 48u);
      if (kind == 0) c = {c[0] % w, c[1] % w, (c[0] % w / 3 + c[1] % w / 5) % side};  // a sheet
      if (kind == 1) c = {(c[0] % w) & ~1u, (c[1] % w) & ~1u, (c[2] % 4) & ~1u};      // a lattice of step 2
      if (kind == 2) c = {c[0] % 12, c[1] % 12, c[2] % 12};                           // a dense ball of cells
      if (kind == 4 && i % 3 != 0) c = {c[0] % 14, c[1] % 14, c[2] % 14};           // a cluster, and scatter
      keys.insert(morton_key(c, d));
    }
    return std::vector<std::uint64_t>(keys.begin(), keys.end());
  };
  for (int d : {3, 6, 9}) {
    for (int kind = 0; kind < 5; ++kind) {
      const auto keys = make(d, kind);
      std::vector<GridPoint> cells;
      std::vector<KdTree<std::int64_t>::Point> at;
      for (auto k : keys) {
        cells.push_back(morton_point(k, d));
        at.push_back({cells.back()[0], cells.back()[1], cells.back()[2]});
      }
      const KdTree<std::int64_t> tree(at);
      for (int shift : {0, 1, 2, 3, 5}) {
        if (shift > d) continue;
        CAPTURE(d);
        CAPTURE(kind);
        CAPTURE(shift);
        LatticeNeighbours lattice(cells, keys, d, shift);
        std::size_t answered = 0, asked = 0;  // for k = 10
        for (int k : {0, 1, 4, 10, 15}) {
          for (std::size_t i = 0; i < cells.size(); ++i) {
            std::array<std::uint32_t, LatticeNeighbours::kMaxK> got{};
            std::array<KdTree<std::int64_t>::Hit, LatticeNeighbours::kMaxK> want{};
            const int kk = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(k), cells.size()));
            const int n = lattice.nearest(i, kk, got.data());
            asked += k == 10;
            if (n < 0) continue;
            answered += k == 10;
            REQUIRE(n == tree.nearest(at[i], kk, want.data()));
            for (int j = 0; j < n; ++j) REQUIRE(got[static_cast<std::size_t>(j)] == want[static_cast<std::size_t>(j)].index);
          }
        }
        // Dense sets are answered cell by cell; scattered deep ones only in
        // buckets large enough to hold their neighbours.
        if (shift == 0 && (kind < 3 || d == 3)) CHECK(answered * 10 >= asked * 9);
        if (kind == 3 && d == 9 && shift == 0) CHECK(answered == 0);
        if (kind == 3 && d == 9 && shift == 5) CHECK(answered * 10 >= asked * 9);
      }
    }
  }
}

TEST_CASE("ChildKeys: the plane's keys handed out beside a quadric's are those of a call with fit 0") {
  std::mt19937_64 rng(5);
  int fitted = 0, compared = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const int q = 1 + static_cast<int>(rng() % 21);
    const int d = static_cast<int>(rng() % static_cast<std::uint64_t>(q));
    const std::uint32_t cells = 1u << d;
    const GridPoint node{static_cast<std::uint32_t>(rng() % cells), static_cast<std::uint32_t>(rng() % cells),
                         static_cast<std::uint32_t>(rng() % cells)};
    const int fit = 6 + static_cast<int>(rng() % (kMaxRankPoints - 5));
    const int k = 1 + static_cast<int>(rng() % static_cast<std::uint64_t>(fit));
    const bool with_gaps = trial % 3 != 0;
    const int gap_from = static_cast<int>(rng() % 2);
    const std::uint64_t span = std::uint64_t{2} << q;
    std::vector<Doubled> nb(static_cast<std::size_t>(fit));
    for (auto& x : nb) {
      for (std::size_t a = 0; a < 3; ++a) x[a] = static_cast<std::int32_t>(rng() % span);
      if (trial % 5 == 0) x[2] = x[0];  // on a plane: some fits are singular, some keys tie
      if (trial % 11 == 0) x[1] = x[0];  // on a line: no quadric
    }
    ChildKeys plane;
    const ChildKeys quadric(node, d, q, nb.data(), k, with_gaps, gap_from, fit, &plane);
    const ChildKeys alone(node, d, q, nb.data(), k, with_gaps, gap_from, fit);
    const ChildKeys want(node, d, q, nb.data(), k, with_gaps, gap_from, 0);
    CHECK(plane.split() == want.split());
    bool differs = false;
    for (int gap = 0; gap <= kFarRanking; ++gap) {
      if (!with_gaps && gap > 0 && gap < kFarRanking) continue;
      for (unsigned mask : {0u, 0x0Fu, static_cast<unsigned>(rng() % 256)}) {
        std::array<int, 8> a{}, b{}, c{}, e{};
        plane.order(mask, gap, a);
        want.order(mask, gap, b);
        quadric.order(mask, gap, c);
        alone.order(mask, gap, e);
        CHECK(a == b);
        CHECK(c == e);  // handing out the plane's keys changes nothing in the quadric's
        differs |= c != b;
        const unsigned occ = 1 + static_cast<unsigned>(rng() % 255);
        CHECK(plane.symbol(mask, gap, occ) == want.symbol(mask, gap, occ));
        ++compared;
      }
    }
    fitted += differs;
  }
  CHECK(compared > 10000);
  CHECK(fitted > 500);  // the quadric did rank otherwise than the plane, often
}

TEST_CASE("quadric ranking (coder 7) round trips, and wins where the surface curves within a few spacings") {
  const int q = 12;
  // A thin torus sampled about 6 points across its tube's radius: a plane
  // through 4 neighbours misses the curve by a good part of the spacing.
  const Split s = level_split(quantize(samples::torus(160, 60, 1.0, 0.2), q), 40);
  CAPTURE(s.coarse.size());
  CAPTURE(s.added.size());
  for (int fit : {1, 5, 6, 10, 15})
    for (int gap : {0, 3})
      for (bool planes : {false, true}) {
        CAPTURE(fit);
        CAPTURE(gap);
        CAPTURE(planes);
        RefinementParams p = params(4, 2);
        p.plane_contexts = planes;
        p.gap = gap;
        p.fit = fit;
        // Read as coder 0, the fit and per-depth flag become slot flags.
        check_coders(encode_refinement(s.coarse, s.added, q, p), s, q, RefineCoder::ranked_octree, RefineCoder::conditional_octree);
        p.depth_gaps = {0, 0, 0, 0, 0, 1, 2, 4, 2, 1, 0, 0};
        check_coders(encode_refinement(s.coarse, s.added, q, p), s, q, RefineCoder::ranked_octree, RefineCoder::conditional_octree);
      }
  // Below 6 neighbours there is no quadric: the tables and symbols of the
  // fit 0, whatever the fit; only the header's fit field (bits 7-10) differs.
  RefinementParams three = params(4, 2);
  three.gap = 3;
  RefinementParams five = three;
  five.fit = 5;
  const auto b3 = encode_refinement(s.coarse, s.added, q, three), b5 = encode_refinement(s.coarse, s.added, q, five);
  const auto bit = [](const std::vector<std::uint8_t>& b, std::size_t i) { return (b[i / 8] >> (7 - i % 8)) & 1; };
  bool same = b5.size() == b3.size() && header_field(b3, 7, 4) == 0 && header_field(b5, 7, 4) == 5;
  for (std::size_t i = 0; same && i < 8 * b3.size(); ++i) same = (i >= 7 && i < 11) || bit(b3, i) == bit(b5, i);
  CHECK(same);
  five.fit = 1;
  CHECK(encode_refinement(s.coarse, s.added, q, five) != b5);  // the header differs
  // The encoder's choice: coder 7 with a quadric (F >= 6), at least 3 %
  // smaller than every ranking without the quadric (a single weight;
  // per-depth weights and pairing aside).
  const RefinementLayer layer = encode_refinement_layer(s.coarse, s.added, q);
  const std::size_t without = smallest_layer(s, q, {0, 1, 2, 3, 4, 6, 8, 12});
  MESSAGE("quadric ranking: ", layer.bytes.size(), " bytes, without: ", without, " (", s.added.size(),
          " added points)");
  CHECK(layer.coder == 7);
  CHECK(header_field(layer.bytes, 7, 4) >= 6);  // F
  CHECK(100 * layer.bytes.size() <= 97 * without);
  CHECK(decode_refinement(layer.bytes.data(), layer.bytes.size(), q, s.coarse, s.added.size(), TableForm::deltas,
                          static_cast<RefineCoder>(layer.coder)) == sorted(s.added));
}

namespace {

// The header fields of a coder 7 layer (spec 8A.1): the weights have 5 bits.
RefinementParams full_params(const std::vector<std::uint8_t>& bytes, int q) {
  RefinementParams p =
      params(static_cast<int>(header_field(bytes, 0, 4)), static_cast<int>(header_field(bytes, 4, 2)) + 1);
  p.plane_contexts = header_field(bytes, 6, 1) == 1;
  p.fit = static_cast<int>(header_field(bytes, 7, 4));
  if (header_field(bytes, 11, 1) == 0) p.gap = static_cast<int>(header_field(bytes, 12, 5));
  else
    for (std::size_t d = 0; d < static_cast<std::size_t>(q); ++d)
      p.depth_gaps.push_back(static_cast<int>(header_field(bytes, 12 + 5 * d, 5)));
  return p;
}

}  // namespace

TEST_CASE("paired tables (coder 7) round trip with every ranking, and the encoder pairs where it saves bits") {
  const int q = 12;
  const Split s = level_split(quantize(samples::torus(160, 60, 1.0, 0.2), q), 40);
  // Forced: pairing with the plain, gap and quadric rankings, tables paired
  // where smaller; read as coder 0, the header is misread.
  for (int fit : {0, 10})
    for (int gap : {0, 3})
      for (bool planes : {false, true}) {
        CAPTURE(fit);
        CAPTURE(gap);
        CAPTURE(planes);
        RefinementParams p = params(fit ? 4 : 1, 3);
        p.plane_contexts = planes;
        p.gap = gap;
        p.fit = fit;
        p.paired = true;
        check_coders(encode_refinement(s.coarse, s.added, q, p), s, q, RefineCoder::ranked_octree, RefineCoder::conditional_octree);
      }
  // The encoder's choice on this surface: coder 7, some tables paired. Its
  // header's fields, forced, give the same bytes with pairing, and a larger
  // layer without.
  const RefinementLayer layer = encode_refinement_layer(s.coarse, s.added, q);
  REQUIRE(layer.coder == 7);
  RefinementParams p = full_params(layer.bytes, q);
  p.paired = true;
  CHECK(encode_refinement(s.coarse, s.added, q, p) == layer.bytes);
  p.paired = false;
  const std::size_t unpaired = encode_refinement(s.coarse, s.added, q, p).size();
  MESSAGE("paired tables: ", layer.bytes.size(), " bytes, unpaired: ", unpaired);
  CHECK(layer.bytes.size() < unpaired);
}

TEST_CASE("far ranking (coder 7) round trips, and wins where added points fill the holes of a volume") {
  const int q = 12;
  // A jittered lattice filling a cube, turned against the grid's axes, its
  // points of even indices added: every neighbour of an added point is
  // coarse, so each added point fills a hole between coarse points, and no
  // surface passes through them.
  std::mt19937_64 rng(9);
  const double ca = std::cos(0.5), sa = std::sin(0.5), cb = std::cos(0.3), sb = std::sin(0.3);
  Points all;
  std::vector<char> even;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      for (int k = 0; k < 12; ++k) {
        const double x = 200.0 * (i - 5.5), y = 200.0 * (j - 5.5), z = 200.0 * (k - 5.5);
        const double x1 = ca * x - sa * y, y1 = sa * x + ca * y;           // about z
        const double y2 = cb * y1 - sb * z, z2 = sb * y1 + cb * z;         // about x
        const double u[3] = {x1, y2, z2};
        GridPoint p{};
        for (std::size_t a = 0; a < 3; ++a)
          p[a] = static_cast<std::uint32_t>(2048.0 + u[a] + static_cast<double>(rng() % 41) - 20.0);
        all.push_back(p);
        even.push_back(i % 2 == 0 && j % 2 == 0 && k % 2 == 0);
      }
  const Split s = split_by(all, [&](std::size_t i) { return even[i] != 0; });
  // Forced: far ranking at every depth, and mixed with gap weights, plane
  // contexts, the quadric; read as coder 0, misread.
  for (int k : {0, 1, 4, 8})
    for (int fit : {0, 10}) {
      CAPTURE(k);
      CAPTURE(fit);
      RefinementParams p = params(k, 2);
      p.fit = fit;
      p.gap = kFarRanking;
      check_coders(encode_refinement(s.coarse, s.added, q, p), s, q, RefineCoder::ranked_octree, RefineCoder::conditional_octree);
      p.gap = 0;
      p.plane_contexts = true;
      p.depth_gaps = {0, 3, 16, 0, 16, 15, 16, 16, 1, 16, 16, 16};
      check_coders(encode_refinement(s.coarse, s.added, q, p), s, q, RefineCoder::ranked_octree, RefineCoder::conditional_octree);
    }
  // The encoder's choice: coder 7, far ranking at the depths below the
  // coarse spacing. Its header, forced, gives a layer of about its size;
  // with weight 0 at those depths (the nearest first) a larger one.
  const RefinementLayer layer = encode_refinement_layer(s.coarse, s.added, q);
  REQUIRE(layer.coder == 7);
  CHECK(decode_refinement(layer.bytes.data(), layer.bytes.size(), q, s.coarse, s.added.size(), TableForm::deltas,
                          RefineCoder::ranked_octree) == sorted(s.added));
  RefinementParams p = full_params(layer.bytes, q);
  p.paired = true;
  const std::size_t far = encode_refinement(s.coarse, s.added, q, p).size();
  CHECK(far <= layer.bytes.size() + 1);  // the forced path pairs tables that save less than a byte
  std::vector<int> gaps = p.depth_gaps.empty() ? std::vector<int>(q, p.gap) : p.depth_gaps;
  CHECK(std::count(gaps.begin(), gaps.end(), kFarRanking) >= 3);
  for (int& g : gaps)
    if (g == kFarRanking) g = 0;
  p.gap = 0;
  p.depth_gaps = gaps;
  const std::size_t near_first = encode_refinement(s.coarse, s.added, q, p).size();
  MESSAGE("far ranking: ", layer.bytes.size(), " bytes (forced ", far, "); without it at those depths: ", near_first);
  CHECK(100 * far < 95 * near_first);
}

TEST_CASE("coder 7: weight 16 ranks farthest first, a weight above 16 is bad_layer, other coders are refused") {
  // q = 1, one coarse point at the origin (child 0), one added point sent as
  // the child of rank 7. Weight 0 (the ranking of 8A.1 with one neighbour):
  // child 0 (coarse), then by distance to the neighbour, nearest first, so
  // rank 7 is child 7. Weight 16: child 0, then farthest first (7; 3, 5, 6;
  // 1, 2, 4, ties by child number), so rank 7 is child 4.
  for (std::uint32_t weight : {0u, 16u, 17u, 31u}) {
    CAPTURE(weight);
    BitWriter w;
    w.put(1, 4);       // neighbours
    w.put(0, 2);       // classes - 1
    w.put(0, 1);       // planes - 1
    w.put(0, 4);       // fit
    w.put(0, 1);       // one weight for every depth
    w.put(weight, 5);  // the weight
    w.put(1, 1);       // depth 0's table: sent,
    w.put(0, 1);       // not paired,
    w.put(1, 1);       // the one-symbol form:
    w.put(7, 8);       // symbol 7, the child of rank 7 alone
    const auto bytes = w.finish();
    const Points coarse{{0, 0, 0}};
    Points got;
    const Status st = status_of([&] {
      got = decode_refinement(bytes.data(), bytes.size(), 1, coarse, 1, TableForm::deltas, RefineCoder::ranked_octree);
    });
    if (weight > 16) {
      CHECK(st == Status::bad_layer);
    } else {
      REQUIRE(st == Status::ok);
      CHECK(got == (weight == 16 ? Points{{1, 0, 0}} : Points{{1, 1, 1}}));
    }
  }
  // The conditional octree has two headers, coders 0 and 7; any other number
  // is not one of its coders (the container's decoder refuses them first, as
  // bad_layer: test_levels).
  const Points coarse{{0, 0, 0}};
  const std::uint8_t bytes[] = {0x13, 0x07};
  for (const int coder : {1, 2, 3, 4, 5, 6, 8}) {
    CAPTURE(coder);
    CHECK(status_of([&] {
      decode_refinement(bytes, 2, 1, coarse, 1, TableForm::deltas, static_cast<RefineCoder>(static_cast<std::uint8_t>(coder)));
    }) == Status::invalid_argument);
  }
}
