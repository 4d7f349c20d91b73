// SPDX-License-Identifier: AGPL-3.0-or-later
#include "pointset/plane_rank.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>

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

// sign(x) * floor(|x| / 2^s) for every value, with the smallest s that makes
// all magnitudes fit in `bits` bits: keeps the products below exact.
template <std::size_t N>
void reduce(std::array<std::int64_t, N>& v, int bits) {
  std::uint64_t m = 0;
  for (std::int64_t x : v) m = std::max(m, static_cast<std::uint64_t>(x < 0 ? -x : x));
  int len = 0;
  while (len < 64 && (m >> len) != 0) ++len;
  const int s = std::max(0, len - bits);
  for (std::int64_t& x : v) x = x < 0 ? -((-x) >> s) : x >> s;
}

}  // namespace

ChildKeys::ChildKeys(const GridPoint& p, int d, int q, const Doubled* neighbours, int k, bool with_gaps,
                     int gap_from) {
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

  int above = 0, below = 0;
  for (std::size_t c = 0; c < 8; ++c) {
    std::int64_t dot = 0, len = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      const std::int64_t bit = (c >> (2 - a)) & 1;
      const std::int64_t v = k * ((2 * std::int64_t{p[a]} + bit) * h + h / 2) - s[a];
      dot += n[a] * v;
      len += v * v;
    }
    t_[c] = dot < 0 ? -dot : dot;
    e_[c] = len;
    above += dot > 0;
    below += dot < 0;
  }
  split_ = std::min(above, below);
  // Gap ranking (spec 8A.4): kappa_c = 32 t_c^2 - G k^2 |n|^2 g_c, with g_c
  // the squared distance from the child's centre to its nearest neighbour.
  // t_c / (k |n|) is the child's distance to the plane, so both terms are
  // squared distances times 32 k^2 |n|^2. Magnitudes (spec): below 2^101.
  const std::int64_t n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  if (!with_gaps || n2 == 0 || gap_from >= k) return;
  weight_ = std::int64_t{k} * k * n2;
  for (std::size_t c = 0; c < 8; ++c) {
    std::int64_t g = INT64_MAX;
    for (int i = gap_from; i < k; ++i) {
      std::int64_t d2 = 0;
      for (std::size_t a = 0; a < 3; ++a) {
        const std::int64_t bit = (c >> (2 - a)) & 1;
        const std::int64_t u = (2 * std::int64_t{p[a]} + bit) * h + h / 2 - neighbours[i][a];
        d2 += u * u;
      }
      g = std::min(g, d2);
    }
    g_[c] = g;
  }
}

void ChildKeys::order(unsigned first_mask, int gap, std::array<int, 8>& order) const {
  std::array<Int128, 8> kappa{};
  const bool gapped = gap > 0 && weight_ > 0;
  if (gapped)
    for (std::size_t c = 0; c < 8; ++c)
      kappa[c] = 32 * static_cast<Int128>(t_[c]) * t_[c] - static_cast<Int128>(gap) * weight_ * g_[c];
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const unsigned ca = (first_mask >> a) & 1u, cb = (first_mask >> b) & 1u;
    if (ca != cb) return ca > cb;
    const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    if (gapped && kappa[ua] != kappa[ub]) return kappa[ua] < kappa[ub];
    if (t_[ua] != t_[ub]) return t_[ua] < t_[ub];
    if (e_[ua] != e_[ub]) return e_[ua] < e_[ub];
    return a < b;
  });
}

void rank_children(const GridPoint& p, int d, int q, const Doubled* neighbours, int k, unsigned first_mask,
                   std::array<int, 8>& order, int* split, int gap, int gap_from) {
  const ChildKeys keys(p, d, q, neighbours, k, gap > 0, gap_from);
  keys.order(first_mask, gap, order);
  if (split) *split = keys.split();
}

}  // namespace hmc::detail
