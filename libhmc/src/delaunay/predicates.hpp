// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Exact geometric predicates on grid points (spec/delaunay.md, section 2).
//
// These are normative code paths: every decision that fixes the
// tetrahedralization of a decoded point set goes through them. They use
// integer arithmetic only (signed 64- and 128-bit), never floating point,
// so the result is the same on every machine and compiler.
//
// Bit budget. Grid coordinates satisfy 0 <= c < 2^21, so a difference of two
// coordinates d satisfies |d| <= 2^21 - 1 < 2^21 (22 bits with sign).
//   orient3d: 2x2 minors |v_y w_z - v_z w_y| < 2 * 2^42 = 2^43 (int64);
//             det = sum of 3 products minor * d, each < 2^64, so
//             |det| < 3 * 2^64 < 2^66 (int128).
//   insphere: lifts |u|^2 = u_x^2 + u_y^2 + u_z^2 < 3 * 2^42 < 2^44 (int64);
//             each 3x3 minor < 2^66 as above; each term lift * minor
//             < 2^44 * 2^66 = 2^110; four terms: |det| < 2^112 (int128,
//             whose range is 2^127).
// All differences are taken relative to the first argument, as in the
// formulas of spec/delaunay.md §2.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hmc/codec.hpp"

namespace hmc::detail {

__extension__ typedef __int128 Int128;

/// An integer 3-vector (a difference of two grid points).
struct IVec3 {
  std::int64_t x, y, z;
};

inline IVec3 sub(const GridPoint& p, const GridPoint& q) noexcept {
  return {static_cast<std::int64_t>(p[0]) - static_cast<std::int64_t>(q[0]),
          static_cast<std::int64_t>(p[1]) - static_cast<std::int64_t>(q[1]),
          static_cast<std::int64_t>(p[2]) - static_cast<std::int64_t>(q[2])};
}

/// det [u; v; w] (rows), exact for |entries| < 2^21.
inline Int128 det3(const IVec3& u, const IVec3& v, const IVec3& w) noexcept {
  const std::int64_t m0 = v.y * w.z - v.z * w.y;
  const std::int64_t m1 = v.z * w.x - v.x * w.z;
  const std::int64_t m2 = v.x * w.y - v.y * w.x;
  return static_cast<Int128>(u.x) * m0 + static_cast<Int128>(u.y) * m1 + static_cast<Int128>(u.z) * m2;
}

inline int sign_of(Int128 v) noexcept { return (v > 0) - (v < 0); }

/// orient3d(a, b, c, d) = det [b - a; c - a; d - a]. Positive when d lies on
/// the side of the plane (a, b, c) from which a, b, c appear counter-
/// clockwise (right-hand rule): orient3d((0,0,0), (1,0,0), (0,1,0), (0,0,1)) = 1.
/// Six times the signed volume of the tetrahedron.
inline Int128 orient3d_value(const GridPoint& a, const GridPoint& b, const GridPoint& c,
                             const GridPoint& d) noexcept {
  return det3(sub(b, a), sub(c, a), sub(d, a));
}
inline int orient3d(const GridPoint& a, const GridPoint& b, const GridPoint& c, const GridPoint& d) noexcept {
  return sign_of(orient3d_value(a, b, c, d));
}

/// insphere(a, b, c, d, e) = -det [u, |u|^2; v, |v|^2; w, |w|^2; t, |t|^2]
/// with u = b - a, v = c - a, w = d - a, t = e - a. When orient3d(a, b, c, d)
/// > 0 it is positive iff e lies strictly inside the sphere through a, b, c,
/// d, negative iff strictly outside, zero iff the five points are
/// cospherical (or coplanar). Equal to -Lambda(a, b, c, d, e), where Lambda
/// is the 5x5 determinant with rows (x, y, z, x^2 + y^2 + z^2, 1).
inline Int128 insphere_value(const GridPoint& a, const GridPoint& b, const GridPoint& c, const GridPoint& d,
                             const GridPoint& e) noexcept {
  const IVec3 u = sub(b, a), v = sub(c, a), w = sub(d, a), t = sub(e, a);
  const std::int64_t lu = u.x * u.x + u.y * u.y + u.z * u.z;
  const std::int64_t lv = v.x * v.x + v.y * v.y + v.z * v.z;
  const std::int64_t lw = w.x * w.x + w.y * w.y + w.z * w.z;
  const std::int64_t lt = t.x * t.x + t.y * t.y + t.z * t.z;
  // Cofactor expansion along the lift column (signs -, +, -, +).
  const Int128 det = -static_cast<Int128>(lu) * det3(v, w, t) + static_cast<Int128>(lv) * det3(u, w, t) -
                     static_cast<Int128>(lw) * det3(u, v, t) + static_cast<Int128>(lt) * det3(u, v, w);
  return -det;
}
inline int insphere(const GridPoint& a, const GridPoint& b, const GridPoint& c, const GridPoint& d,
                    const GridPoint& e) noexcept {
  return sign_of(insphere_value(a, b, c, d, e));
}

/// The perturbed in-sphere test of spec/delaunay.md section 3: the sign of
/// insphere for the lifts x^2 + y^2 + z^2 - eps_i, where i is a point's index
/// in canonical order and eps_0 >> eps_1 >> ... > 0 are infinitesimal.
///
/// `v` holds five indices into `pts` (the points a, b, c, d, e in that
/// order). If the unperturbed insphere is zero, the result is the sign of
/// (-1)^r * orient3d(the other four, in their order) for the position r
/// whose point has the smallest index, then the next smallest, and so on.
/// Never zero unless all five points are coplanar; in particular never zero
/// when orient3d(a, b, c, d) != 0.
inline int insphere_perturbed(const std::vector<GridPoint>& pts, const std::array<std::uint32_t, 5>& v) noexcept {
  const int s = insphere(pts[v[0]], pts[v[1]], pts[v[2]], pts[v[3]], pts[v[4]]);
  if (s != 0) return s;
  // Positions 0..4 by ascending point index (insertion sort of five).
  std::array<int, 5> order{0, 1, 2, 3, 4};
  for (int i = 1; i < 5; ++i)
    for (int j = i; j > 0 && v[order[j - 1]] > v[order[j]]; --j) std::swap(order[j - 1], order[j]);
  for (int r : order) {
    std::array<std::uint32_t, 4> rest{};
    for (int k = 0, m = 0; k < 5; ++k)
      if (k != r) rest[m++] = v[k];
    const int o = orient3d(pts[rest[0]], pts[rest[1]], pts[rest[2]], pts[rest[3]]);
    if (o != 0) return (r & 1) ? -o : o;
  }
  return 0;
}

}  // namespace hmc::detail
