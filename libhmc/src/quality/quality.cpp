// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Element quality tests of the thesis (§3.5). Informative only: nothing here
// influences what the encoder writes or the decoder reconstructs. See
// spec/informative-quality.md for the definitions and their derivations.
#include "hmc/quality.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hmc::quality {

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
// A measure (twice the area, six times the volume) no larger than this many
// ulps of its natural scale (Lmax², Lmax³) is indistinguishable from rounding
// noise in the edge vectors, so the element is treated as degenerate and
// scores exactly 0. Being relative, the test is itself scale invariant.
constexpr double kDegenerateUlps = 64.0;

Vec3 sub(const Vec3& p, const Vec3& q) noexcept { return {p[0] - q[0], p[1] - q[1], p[2] - q[2]}; }
double dot(const Vec3& u, const Vec3& v) noexcept { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; }
Vec3 cross(const Vec3& u, const Vec3& v) noexcept {
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}
double norm(const Vec3& u) noexcept { return std::sqrt(dot(u, u)); }

// Scores are mathematically in [0,1]; the clamp only absorbs rounding (an
// ideal element may come out as 1 + 1 ulp). `!(x > 0)` also maps NaN, which
// non-finite input coordinates would produce, to 0.
double clamp_score(double x) noexcept {
  if (!(x > 0)) return 0;
  return x < 1 ? x : 1;
}

// What the four tetrahedron tests share. All lengths come from difference
// vectors, so absolute position never enters the arithmetic.
struct Tet {
  Vec3 p[4];
  double len[4][4];   // edge lengths, len[i][j] = |p_j − p_i|
  double det6 = 0;    // |6V|
  double lmax = 0;
  double sum_l2 = 0;  // Σ L² over the six edges
  bool degenerate = true;

  Tet(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept : p{a, b, c, d} {
    for (int i = 0; i < 4; ++i) {
      len[i][i] = 0;
      for (int j = i + 1; j < 4; ++j) {
        const Vec3 e = sub(p[j], p[i]);
        const double l2 = dot(e, e);
        len[i][j] = len[j][i] = std::sqrt(l2);
        sum_l2 += l2;
        lmax = std::max(lmax, len[i][j]);
      }
    }
    const Vec3 u = sub(b, a), v = sub(c, a), w = sub(d, a);
    det6 = std::abs(dot(u, cross(v, w)));  // |V| makes orientation irrelevant
    degenerate = !(det6 > kDegenerateUlps * kEps * lmax * lmax * lmax);
  }

  // Sum of the four face areas, times two.
  double twice_area() const noexcept {
    static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    double s = 0;
    for (const auto& f : kFace) s += norm(cross(sub(p[f[1]], p[f[0]]), sub(p[f[2]], p[f[0]])));
    return s;
  }
};

// r_in = 3V / A: the tetrahedron splits into four cones of height r_in over
// its faces. With det6 = 6V and s = 2A this is det6 / s.
double inradius(const Tet& t) noexcept {
  const double s = t.twice_area();
  return s > 0 ? t.det6 / s : 0;
}

// (l_ij + l_ik)² − l_jk² for vertex i and its edges to j and k. By the law of
// cosines l_jk² = |u|² + |v|² − 2u·v (u, v the edge vectors from i), so this
// is 2(|u||v| + u·v): no squared sums of rounded lengths. It vanishes only for
// a straight face angle at i, in which case the volume is 0 already.
double solid_angle_factor(const Tet& t, int i, int j, int k) noexcept {
  const double f = 2 * (t.len[i][j] * t.len[i][k] + dot(sub(t.p[j], t.p[i]), sub(t.p[k], t.p[i])));
  return f > 0 ? f : 0;
}

}  // namespace

double triangle_angle(const Vec3& a, const Vec3& b, const Vec3& c) noexcept {
  const Vec3 ab = sub(b, a), ac = sub(c, a), bc = sub(c, b);
  const double lmax2 = std::max({dot(ab, ab), dot(ac, ac), dot(bc, bc)});
  const double twice_area = norm(cross(ab, ac));
  if (!(twice_area > kDegenerateUlps * kEps * lmax2)) return 0;
  // atan2(|u×v|, u·v) keeps full relative accuracy for small and for
  // near-straight angles, where acos of a rounded cosine does not.
  const Vec3 ba = sub(a, b), ca = sub(a, c), cb = sub(b, c);
  const double at_a = std::atan2(twice_area, dot(ab, ac));
  const double at_b = std::atan2(norm(cross(ba, bc)), dot(ba, bc));
  const double at_c = std::atan2(norm(cross(ca, cb)), dot(ca, cb));
  const double theta_min = std::min({at_a, at_b, at_c});
  // θmin ≤ 60°, so 3θmin/2 ≤ 90° and the sine is increasing on that range.
  return clamp_score(std::sin(1.5 * theta_min));
}

double triangle_edge_ratio(const Vec3& a, const Vec3& b, const Vec3& c) noexcept {
  const Vec3 ab = sub(b, a), ac = sub(c, a), bc = sub(c, b);
  const double l2[3] = {dot(ab, ab), dot(ac, ac), dot(bc, bc)};
  const double lmax2 = std::max({l2[0], l2[1], l2[2]});
  // Collinear triangles have a positive Lmin/Lmax; they are degenerate all
  // the same and score 0 like in every other test.
  if (!(norm(cross(ab, ac)) > kDegenerateUlps * kEps * lmax2)) return 0;
  return clamp_score(std::sqrt(std::min({l2[0], l2[1], l2[2]}) / lmax2));
}

double tet_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept {
  const Tet t(a, b, c, d);
  if (t.degenerate) return 0;
  // Circumcentre relative to a: (|u|²(v×w) + |v|²(w×u) + |w|²(u×v)) / (2·u·(v×w)),
  // hence R_out = |that numerator| / (2·det6) = |numerator| / (12V).
  const Vec3 u = sub(b, a), v = sub(c, a), w = sub(d, a);
  const Vec3 vw = cross(v, w), wu = cross(w, u), uv = cross(u, v);
  const double uu = dot(u, u), vv = dot(v, v), ww = dot(w, w);
  const Vec3 num = {uu * vw[0] + vv * wu[0] + ww * uv[0], uu * vw[1] + vv * wu[1] + ww * uv[1],
                    uu * vw[2] + vv * wu[2] + ww * uv[2]};
  const double r_out = norm(num) / (2 * t.det6);
  const double r_in = inradius(t);
  return r_out > 0 ? clamp_score(3 * r_in / r_out) : 0;
}

double tet_inradius_edge(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept {
  const Tet t(a, b, c, d);
  if (t.degenerate) return 0;
  return clamp_score(2 * std::sqrt(6.0) * inradius(t) / t.lmax);
}

double tet_volume_edge(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept {
  const Tet t(a, b, c, d);
  if (t.degenerate) return 0;
  const double k = std::cbrt(t.det6 / 2);  // (3V)^(1/3), 3V = det6 / 2
  return clamp_score(12 * k * k / t.sum_l2);
}

double tet_min_solid_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept {
  const Tet t(a, b, c, d);
  if (t.degenerate) return 0;
  static constexpr int kOthers[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  double min_sin = 1;
  for (int i = 0; i < 4; ++i) {
    const int j = kOthers[i][0], k = kOthers[i][1], l = kOthers[i][2];
    // Square roots taken one factor at a time keep the product of three
    // length⁴ terms away from overflow and underflow at extreme scales.
    const double den = std::sqrt(solid_angle_factor(t, i, j, k)) * std::sqrt(solid_angle_factor(t, i, j, l)) *
                       std::sqrt(solid_angle_factor(t, i, k, l));
    if (!(den > 0)) return 0;
    min_sin = std::min(min_sin, 2 * t.det6 / den);  // 12V = 2·det6
  }
  return clamp_score(1.5 * std::sqrt(6.0) * min_sin);
}

namespace {

// Running sums for one Stats; the mean is formed once at the end.
struct Accumulator {
  Stats s;
  double sum = 0;

  void add(double q) {
    if (s.count == 0) {
      s.min = s.max = q;
    } else {
      s.min = std::min(s.min, q);
      s.max = std::max(s.max, q);
    }
    ++s.count;
    sum += q;
    // Scores are in [0,1]; a score of exactly 1 belongs to the last bin.
    const auto bin = static_cast<std::size_t>(q * 10);
    ++s.histogram[std::min<std::size_t>(bin, 9)];
  }

  Stats finish() const {
    Stats out = s;
    if (out.count > 0) out.mean = sum / static_cast<double>(out.count);
    return out;
  }
};

}  // namespace

MeshQuality evaluate(const Mesh& mesh) {
  const std::size_t n = mesh.points.size();
  Accumulator tri_angle, tri_edge, qt1, qt2, qt3, qt4;
  for (const Triangle& tri : mesh.triangles) {
    if (tri[0] >= n || tri[1] >= n || tri[2] >= n) continue;
    const Vec3& a = mesh.points[tri[0]];
    const Vec3& b = mesh.points[tri[1]];
    const Vec3& c = mesh.points[tri[2]];
    tri_angle.add(triangle_angle(a, b, c));
    tri_edge.add(triangle_edge_ratio(a, b, c));
  }
  for (const Tetrahedron& tet : mesh.tetrahedra) {
    if (tet[0] >= n || tet[1] >= n || tet[2] >= n || tet[3] >= n) continue;
    const Vec3& a = mesh.points[tet[0]];
    const Vec3& b = mesh.points[tet[1]];
    const Vec3& c = mesh.points[tet[2]];
    const Vec3& d = mesh.points[tet[3]];
    qt1.add(tet_radius_ratio(a, b, c, d));
    qt2.add(tet_inradius_edge(a, b, c, d));
    qt3.add(tet_volume_edge(a, b, c, d));
    qt4.add(tet_min_solid_angle(a, b, c, d));
  }
  return {tri_angle.finish(), tri_edge.finish(), qt1.finish(), qt2.finish(), qt3.finish(), qt4.finish()};
}

}  // namespace hmc::quality
