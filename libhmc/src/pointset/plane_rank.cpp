// SPDX-License-Identifier: AGPL-3.0-or-later
#include "pointset/plane_rank.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace hmc::detail {

int popcount8(unsigned v) {
  int n = 0;
  for (; v; v &= v - 1) ++n;
  return n;
}

OccupancyOrder::OccupancyOrder() {
  int n = 0;
  for (int bits = 1; bits <= 8; ++bits)
    for (unsigned o = 1; o < 256; ++o)
      if (popcount8(o) == bits) {
        index[o] = static_cast<std::uint8_t>(n);
        occupancy[static_cast<std::size_t>(n++)] = static_cast<std::uint8_t>(o);
      }
}

const OccupancyOrder& occupancy_order() {
  static const OccupancyOrder order;
  return order;
}

namespace {

__extension__ typedef __int128 Int128;
__extension__ typedef unsigned __int128 UInt128;

// The rank of each of eight distinct keys, the number of smaller ones: each
// pair compared once, without branches.
std::array<int, 8> ranks_of(const std::array<UInt128, 8>& keys) {
  std::array<int, 8> rank{};
  for (std::size_t c = 1; c < 8; ++c)
    for (std::size_t o = 0; o < c; ++o) {
      const int before = keys[o] < keys[c] ? 1 : 0;
      rank[c] += before;
      rank[o] += 1 - before;
    }
  return rank;
}

// sign(x) * floor(|x| / 2^s) for every value, with the smallest s that makes
// all magnitudes fit in `bits` bits: keeps the products below exact.
template <std::size_t N>
void reduce(std::array<std::int64_t, N>& v, int bits) {
  std::uint64_t m = 0;
  for (std::int64_t x : v) m = std::max(m, static_cast<std::uint64_t>(x < 0 ? -x : x));
  const int len = m == 0 ? 0 : 64 - __builtin_clzll(m);  // m's bit length
  const int s = std::max(0, len - bits);
  for (std::int64_t& x : v) x = x < 0 ? -((-x) >> s) : x >> s;
}

// Coordinates of a point relative to the node's centre in the frame of
// spec 8A.1: u and v along e_a x n and e_b x n (a < b the axes other than
// the normal's dominant axis j), both perpendicular to n, and the height w
// along n itself. Exact integers (below 2^46 in magnitude), so exact doubles.
struct Frame {
  std::array<std::int64_t, 3> t, b, n;
  std::array<double, 3> of(const std::array<std::int64_t, 3>& delta) const {
    auto dot = [&](const std::array<std::int64_t, 3>& x) {
      return static_cast<double>(delta[0] * x[0] + delta[1] * x[1] + delta[2] * x[2]);
    };
    return {dot(t), dot(b), dot(n)};
  }
};

Frame frame_of(const std::array<std::int64_t, 3>& n, std::size_t j) {
  const std::size_t a = j == 0 ? 1 : 0, b = j == 2 ? 1 : 2;
  // e_x x n = (0, -n_z, n_y), e_y x n = (n_z, 0, -n_x), e_z x n = (-n_y, n_x, 0).
  auto cross = [&](std::size_t axis) {
    std::array<std::int64_t, 3> c{0, 0, 0};
    c[(axis + 1) % 3] = -n[(axis + 2) % 3];
    c[(axis + 2) % 3] = n[(axis + 1) % 3];
    return c;
  };
  return {cross(a), cross(b), n};
}

// The quadric of spec 8A.1 through the points neighbours[0 .. f): the height
// w as c0 + c1 u + c2 v + c3 u^2 + c4 uv + c5 v^2 by least squares, in
// binary64 and in the operation order the spec writes (the build sets
// -ffp-contract=off: no fused multiply-add). False when the normal equations
// are (nearly) singular: a pivot of their L D L^T factorization is at most
// 2^-40 times its diagonal entry.
bool fit_quadric(const Doubled* neighbours, int f, const std::array<std::int64_t, 3>& o, const Frame& frame,
                 std::array<double, 6>& coef) {
  // The normal equations' sums m[x][y] = sum_i beta_x beta_y (y >= x) and
  // r[x] = sum_i beta_x w, beta = (1, u, v, u^2, uv, v^2), each summed in
  // point order. Products with beta_0 = 1 are exact, so m[0][3..5] are the
  // same sums as m[1][1], m[1][2], m[2][2] and m[0][0] is f: 23 sums, kept
  // in pairs of lanes (each lane an IEEE product and sum of its own, the
  // same result as one sum at a time).
  typedef double Pair __attribute__((vector_size(16)));
  Pair sum[12] = {};
  for (int i = 0; i < f; ++i) {
    const auto x = frame.of({neighbours[i][0] - o[0], neighbours[i][1] - o[1], neighbours[i][2] - o[2]});
    const double u = x[0], v = x[1], w = x[2];
    const Pair uv = {u, v};
    const Pair a = u * uv;            // u^2, uv
    const Pair b = {v * v, w};        // v^2, w
    const Pair c = {a[1], b[0]};      // uv, v^2
    const Pair e = {w, b[0]};         // w, v^2
    const Pair term[12] = {uv, a, b, u * a, u * b, v * a, v * b, a[0] * a, a[0] * b, a[1] * c, c * e, Pair{b[0] * w, 0.0}};
    for (std::size_t at = 0; at < 12; ++at) sum[at] = sum[at] + term[at];
  }
  // sum[0] = (u, v), [1] = (u^2, uv), [2] = (v^2, w), [3] = u (u^2, uv),
  // [4] = u (v^2, w), [5] = v (u^2, uv), [6] = v (v^2, w), [7] = u^2 (u^2,
  // uv), [8] = u^2 (v^2, w), [9] = uv (uv, v^2), [10] = (uv w, v^4), [11] =
  // (v^2 w, 0).
  const double su = sum[0][0], sv = sum[0][1], suu = sum[1][0], suv = sum[1][1], svv = sum[2][0];
  const double m[6][6] = {{static_cast<double>(f), su, sv, suu, suv, svv},
                          {su, suu, suv, sum[3][0], sum[3][1], sum[4][0]},
                          {sv, suv, svv, sum[5][0], sum[5][1], sum[6][0]},
                          {suu, sum[3][0], sum[5][0], sum[7][0], sum[7][1], sum[8][0]},
                          {suv, sum[3][1], sum[5][1], sum[7][1], sum[9][0], sum[9][1]},
                          {svv, sum[4][0], sum[6][0], sum[8][0], sum[9][1], sum[10][1]}};
  const double r[6] = {sum[2][1], sum[4][1], sum[6][1], sum[8][1], sum[10][0], sum[11][0]};
  // m = L D L^T, L unit lower triangular (l[z][x], x < z).
  double l[6][6] = {}, dg[6] = {};
  for (std::size_t x = 0; x < 6; ++x) {
    double acc = m[x][x];
    for (std::size_t y = 0; y < x; ++y) acc = acc - l[x][y] * l[x][y] * dg[y];
    if (!(acc > m[x][x] * 0x1p-40)) return false;
    dg[x] = acc;
    for (std::size_t z = x + 1; z < 6; ++z) {
      double e = m[x][z];
      for (std::size_t y = 0; y < x; ++y) e = e - l[z][y] * l[x][y] * dg[y];
      l[z][x] = e / dg[x];
    }
  }
  double y[6];
  for (std::size_t x = 0; x < 6; ++x) {
    double acc = r[x];
    for (std::size_t z = 0; z < x; ++z) acc = acc - l[x][z] * y[z];
    y[x] = acc;
  }
  for (std::size_t x = 6; x-- > 0;) {
    double acc = y[x] / dg[x];
    for (std::size_t z = x + 1; z < 6; ++z) acc = acc - l[z][x] * coef[z];
    coef[x] = acc;
  }
  return true;
}

}  // namespace

ChildKeys::ChildKeys(const GridPoint& p, int d, int q, const Doubled* neighbours, int k, bool with_gaps,
                     int gap_from, int fit, ChildKeys* plane) {
  const std::int64_t h = std::int64_t{1} << (q - d);  // node side
  std::array<std::int64_t, 3> s{0, 0, 0};
  std::array<std::int64_t, 6> ss{};  // xx yy zz xy xz yz
  for (int i = 0; i < k; ++i) {
    const Doubled& g = neighbours[i];
    for (std::size_t a = 0; a < 3; ++a) s[a] += g[a];
    ss[0] += std::int64_t{g[0]} * g[0], ss[1] += std::int64_t{g[1]} * g[1], ss[2] += std::int64_t{g[2]} * g[2];
    ss[3] += std::int64_t{g[0]} * g[1], ss[4] += std::int64_t{g[0]} * g[2], ss[5] += std::int64_t{g[1]} * g[2];
  }
  // k^2 times the covariance; the dominant column of its adjugate is (up to
  // the reductions that keep it exact in 64 bits) the normal of the plane
  // that fits the neighbours best, and 0 for a single neighbour.
  std::array<std::int64_t, 6> m{k * ss[0] - s[0] * s[0], k * ss[1] - s[1] * s[1], k * ss[2] - s[2] * s[2],
                                k * ss[3] - s[0] * s[1], k * ss[4] - s[0] * s[2], k * ss[5] - s[1] * s[2]};
  reduce(m, 31);
  const std::int64_t xx = m[0], yy = m[1], zz = m[2], xy = m[3], xz = m[4], yz = m[5];
  const std::array<std::int64_t, 3> diag{yy * zz - yz * yz, xx * zz - xz * xz, xx * yy - xy * xy};
  const std::int64_t axy = xz * yz - xy * zz, axz = xy * yz - xz * yy, ayz = xy * xz - xx * yz;
  std::size_t j = 0;
  for (std::size_t a = 1; a < 3; ++a)
    if (diag[a] > diag[j]) j = a;
  std::array<std::int64_t, 3> n = j == 0 ? std::array<std::int64_t, 3>{diag[0], axy, axz}
                                  : j == 1 ? std::array<std::int64_t, 3>{axy, diag[1], ayz}
                                           : std::array<std::int64_t, 3>{axz, ayz, diag[2]};
  reduce(n, 20);

  std::array<std::int64_t, 8> t{}, e{};  // plane (or quadric) and centroid keys
  int above = 0, below = 0;
  for (std::size_t c = 0; c < 8; ++c) {
    std::int64_t dot = 0, len = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      const std::int64_t bit = (c >> (2 - a)) & 1;
      const std::int64_t v = k * ((2 * std::int64_t{p[a]} + bit) * h + h / 2) - s[a];
      dot += n[a] * v;
      len += v * v;
    }
    t[c] = dot < 0 ? -dot : dot;
    e[c] = len;
    above += dot > 0;
    below += dot < 0;
  }
  split_ = std::min(above, below);
  // The quadric keys (spec 8A.1): t_c = k |w_c - quadric(u_c, v_c)|, the
  // child's height above the quadric in the plane key's units (w is |n|
  // times a distance along the normal), truncated, at most 2^47.
  const Frame frame = frame_of(n, j);
  std::array<double, 6> coef{};
  const std::array<std::int64_t, 8> t_plane = t;
  const bool quadric = fit >= 6 && fit <= kMaxRankPoints && n[j] > 0 &&
                       fit_quadric(neighbours, fit, {2 * std::int64_t{p[0]} * h + h, 2 * std::int64_t{p[1]} * h + h,
                                                     2 * std::int64_t{p[2]} * h + h}, frame, coef);
  if (quadric) {
    // The children's offsets from the centre are (+-h/2, +-h/2, +-h/2), so
    // their frame coordinates are sums and differences of three columns.
    const std::int64_t half = h / 2;
    std::array<std::array<std::int64_t, 3>, 3> column{};
    for (std::size_t a = 0; a < 3; ++a) column[a] = {half * frame.t[a], half * frame.b[a], half * frame.n[a]};
    for (std::size_t c = 0; c < 8; ++c) {
      std::array<std::int64_t, 3> at{0, 0, 0};
      for (std::size_t a = 0; a < 3; ++a)
        for (std::size_t i = 0; i < 3; ++i) at[i] += ((c >> (2 - a)) & 1) != 0 ? column[a][i] : -column[a][i];
      const std::array<double, 3> x{static_cast<double>(at[0]), static_cast<double>(at[1]),
                                    static_cast<double>(at[2])};
      const double u = x[0], v = x[1];
      const double fitted = coef[0] + coef[1] * u + coef[2] * v + coef[3] * (u * u) + coef[4] * (u * v) +
                            coef[5] * (v * v);
      const double key = std::fabs(x[2] - fitted) * static_cast<double>(k);
      t[c] = key < 0x1p47 ? static_cast<std::int64_t>(key) : std::int64_t{1} << 47;
    }
  }
  // Without `with_gaps` no ranking uses g_c: left 0, the far keys order as
  // (t, e, c), the ranking of spec 8A.1 without neighbours.
  // Per point, the squared offsets along each axis of the children's two
  // centre coordinates, (2X + bit)·h + h/2 for bit 0 and 1, then each
  // child's sum of its three: the same integers, a third of the products.
  std::array<std::int64_t, 8> g{};  // 0 without neighbours beyond gap_from
  if (with_gaps && gap_from < k) {
    g.fill(INT64_MAX);
    for (int i = gap_from; i < k; ++i) {
      std::int64_t sq[3][2];
      for (std::size_t a = 0; a < 3; ++a) {
        const std::int64_t u = 2 * std::int64_t{p[a]} * h + h / 2 - neighbours[i][a];
        sq[a][0] = u * u;
        sq[a][1] = (u + h) * (u + h);
      }
      for (std::size_t c = 0; c < 8; ++c)
        g[c] = std::min(g[c], sq[0][(c >> 2) & 1] + sq[1][(c >> 1) & 1] + sq[2][c & 1]);
    }
  }
  const std::int64_t n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  const bool gapped = with_gaps && n2 != 0 && gap_from < k;
  const std::int64_t weight = std::int64_t{k} * k * n2;
  finish(t, e, g, gapped, weight);
  if (plane) {
    // The same keys with the plane's t_c (no quadric): everything else is
    // what the plane ranking computes too.
    plane->split_ = split_;
    if (quadric)
      plane->finish(t_plane, e, g, gapped, weight);
    else
      plane->tie_ = tie_, plane->gapped_ = gapped_, plane->base_ = base_, plane->step_ = step_, plane->far_ = far_;
  }
}

__attribute__((always_inline)) inline void ChildKeys::finish(const std::array<std::int64_t, 8>& t,
                                                             const std::array<std::int64_t, 8>& e,
                                                             const std::array<std::int64_t, 8>& g, bool gapped,
                                                             std::int64_t weight) {
  // Each child's place in the order by (t_c, e_c, c), the ranking's last
  // keys whatever the gap weight: the three packed into one integer (t_c
  // < 2^49 above bit 64, e_c < 2^56 from bit 3, c in bits 0-2).
  std::array<UInt128, 8> packed{};
  for (std::size_t c = 0; c < 8; ++c)
    packed[c] = static_cast<UInt128>(t[c]) << 64 | static_cast<UInt128>(static_cast<std::uint64_t>(e[c]) << 3 | c);
  const std::array<int, 8> place = ranks_of(packed);
  for (std::size_t c = 0; c < 8; ++c) tie_[c] = static_cast<std::uint8_t>(place[c]);
  // Far ranking (spec 8A.1): the larger g_c first, then the place by (t, e,
  // c): 2^47 - g_c (g_c < 3 * 2^44) from bit 3, the place in bits 0-2.
  for (std::size_t c = 0; c < 8; ++c)
    far_[c] = ((std::uint64_t{1} << 47) - static_cast<std::uint64_t>(g[c])) << 3 | tie_[c];
  // Gap ranking (spec 8A.1): kappa_c = 32 t_c^2 - G k^2 |n|^2 g_c, with g_c
  // the squared distance from the child's centre to its nearest neighbour.
  // t_c / (k |n|) is the child's distance to the plane, so both terms are
  // squared distances times 32 k^2 |n|^2. Magnitudes (spec): below 2^104.
  // order() sorts the children by one integer each, (not in the mask, then
  // kappa_c, then the place by (t, e, c)): kappa_c + 2^106 from bit 3, the
  // place in bits 0-2, the mask in bit 112; here base_c = that integer for
  // G = 0 and step_c = its decrease per unit of G.
  gapped_ = gapped;
  if (!gapped) return;
  for (std::size_t c = 0; c < 8; ++c) {
    base_[c] = (static_cast<UInt128>(32 * static_cast<Int128>(t[c]) * t[c] + (Int128{1} << 106)) << 3) + tie_[c];
    step_[c] = static_cast<UInt128>(static_cast<Int128>(weight) * g[c]) << 3;
  }
}

// The sort keys of the eight children (see the constructor), distinct.
void ChildKeys::keys(unsigned first_mask, int gap, std::array<UInt128, 8>& out) const {
  // The weight's keys for all eight children (one test of the weight, not
  // eight), then the children outside first_mask after all the others.
  if (gap == kFarRanking) {
    for (std::size_t c = 0; c < 8; ++c) out[c] = far_[c];
  } else if (gap > 0 && gapped_) {
    const auto g = static_cast<std::uint64_t>(gap);
    for (std::size_t c = 0; c < 8; ++c) out[c] = base_[c] - step_[c] * g;
  } else {
    for (std::size_t c = 0; c < 8; ++c) out[c] = tie_[c];
  }
  for (std::size_t c = 0; c < 8; ++c)
    if (!((first_mask >> c) & 1u)) out[c] += UInt128{1} << 112;
}

void ChildKeys::order(unsigned first_mask, int gap, std::array<int, 8>& order) const {
  std::array<UInt128, 8> k{};
  keys(first_mask, gap, k);
  const std::array<int, 8> place = ranks_of(k);  // the keys are distinct
  for (std::size_t c = 0; c < 8; ++c) order[static_cast<std::size_t>(place[c])] = static_cast<int>(c);
}

std::uint8_t ChildKeys::symbol(unsigned first_mask, int gap, unsigned occupancy) const {
  std::uint8_t out = 0;
  symbols(first_mask, &gap, 1, occupancy, &out);
  return out;
}

void ChildKeys::symbols(unsigned first_mask, const int* gaps, std::size_t n, unsigned occupancy,
                        std::uint8_t* out) const {
  const auto& index = occupancy_order().index;
  // The keys of keys(): the weight's key, plus 2^112 for the children
  // outside first_mask. Every key is below 2^113, so when all children or
  // none are in first_mask the lift is the same for all and changes no
  // comparison: it is left out.
  std::array<UInt128, 8> lift{};
  if ((first_mask & 0xFFu) != 0 && (first_mask & 0xFFu) != 0xFFu)
    for (std::size_t c = 0; c < 8; ++c)
      if (!((first_mask >> c) & 1u)) lift[c] = UInt128{1} << 112;
  std::array<std::size_t, 8> occupied{};
  std::size_t m = 0;
  for (unsigned occ = occupancy & 0xFFu; occ != 0; occ &= occ - 1)
    occupied[m++] = static_cast<std::size_t>(__builtin_ctz(occ));
  const auto symbol_of = [&](const std::array<UInt128, 8>& k) {
    unsigned ranked = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const UInt128 kc = k[occupied[i]];
      int rank = 0;
      for (std::size_t o = 0; o < 8; ++o) rank += k[o] < kc;
      ranked |= 1u << rank;
    }
    return index[ranked];
  };
  // gapped: base_ - step_ * at + lift, for the weight `at` (wrapping as
  // keys() does: the same residues, so the same keys).
  std::array<UInt128, 8> gapped{}, other{};
  for (std::size_t c = 0; c < 8; ++c) gapped[c] = base_[c] + lift[c];
  int at = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const int gap = gaps[j];
    if (gap == kFarRanking) {
      for (std::size_t c = 0; c < 8; ++c) other[c] = far_[c] + lift[c];
      out[j] = symbol_of(other);
    } else if (gap > 0 && gapped_) {
      const int delta = gap - at;
      if (delta == 1) {
        for (std::size_t c = 0; c < 8; ++c) gapped[c] -= step_[c];
      } else if (delta > 0) {
        const auto times = static_cast<std::uint64_t>(delta);
        for (std::size_t c = 0; c < 8; ++c) gapped[c] -= step_[c] * times;
      } else if (delta < 0) {
        const auto times = static_cast<std::uint64_t>(-delta);
        for (std::size_t c = 0; c < 8; ++c) gapped[c] += step_[c] * times;
      }
      at = gap;
      out[j] = symbol_of(gapped);
    } else {
      for (std::size_t c = 0; c < 8; ++c) other[c] = tie_[c] + lift[c];
      out[j] = symbol_of(other);
    }
  }
}

void rank_children(const GridPoint& p, int d, int q, const Doubled* neighbours, int k, unsigned first_mask,
                   std::array<int, 8>& order, int* split, int gap, int gap_from) {
  const ChildKeys keys(p, d, q, neighbours, k, gap > 0, gap_from);
  keys.order(first_mask, gap, order);
  if (split) *split = keys.split();
}

}  // namespace hmc::detail
