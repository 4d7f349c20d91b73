// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Element quality tests (thesis §3.5). Every expected value below is derived
// by hand in the comment next to it, from the geometry of the element and the
// definitions in hmc/quality.hpp — never from the implementation:
//   QT1 = 3·r_in/R_out          QT2 = 2√6·r_in/L_max
//   QT3 = 12·(3V)^(2/3)/ΣL²     QT4 = (3√6/2)·min_i sin(Ω_i/2),
//   sin(Ω_i/2) = 12V / sqrt(Π_{j<k; j,k≠i} ((l_ij + l_ik)² − l_jk²)),
//   r_in = 3V/A (A = total face area), triangle_angle = sin(3θmin/2),
//   triangle_edge_ratio = Lmin/Lmax.
// The closed forms of the parametric families were also cross-checked, while
// writing this file, against a generic computation that used a linear solve
// for the circumcentre and the atan2 (Van Oosterom–Strackee) form of the
// solid angle — a route independent of both the formulas above and the code.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "hmc/quality.hpp"
#include "samples.hpp"
#include "support/temp_dir.hpp"

using hmc::Vec3;
namespace q = hmc::quality;

namespace {

using Tet4 = std::array<Vec3, 4>;
using Tri3 = std::array<Vec3, 3>;
using Scores = std::array<double, 4>;  // QT1..QT4

const double kSqrt2 = std::sqrt(2.0);
const double kSqrt3 = std::sqrt(3.0);
const double kSqrt6 = std::sqrt(6.0);
constexpr double kPi = 3.14159265358979323846;

bool rel_eq(double got, double want, double tol) { return std::abs(got - want) <= tol * std::abs(want); }

std::string describe(double got, double want) {
  std::ostringstream os;
  os.precision(17);
  os << "got " << got << ", expected " << want;
  return os.str();
}

#define CHECK_REL(got, want, tol) CHECK_MESSAGE(rel_eq((got), (want), (tol)), describe((got), (want)))

Scores scores(const Tet4& t) {
  return {q::tet_radius_ratio(t[0], t[1], t[2], t[3]), q::tet_inradius_edge(t[0], t[1], t[2], t[3]),
          q::tet_volume_edge(t[0], t[1], t[2], t[3]), q::tet_min_solid_angle(t[0], t[1], t[2], t[3])};
}

void check_scores(const Tet4& t, const Scores& want, double tol) {
  const Scores got = scores(t);
  for (std::size_t i = 0; i < 4; ++i) {
    INFO("QT" << (i + 1));
    CHECK_REL(got[i], want[i], tol);
  }
}

// Rotation by `angle` about the unit vector along `axis` (Rodrigues).
std::array<Vec3, 3> rotation(Vec3 axis, double angle) {
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  const double x = axis[0] / n, y = axis[1] / n, z = axis[2] / n;
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  return {{{t * x * x + c, t * x * y - s * z, t * x * z + s * y},
           {t * x * y + s * z, t * y * y + c, t * y * z - s * x},
           {t * x * z - s * y, t * y * z + s * x, t * z * z + c}}};
}

Vec3 apply(const std::array<Vec3, 3>& m, const Vec3& p) {
  Vec3 r{};
  for (std::size_t i = 0; i < 3; ++i) r[i] = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2];
  return r;
}

// p ↦ s·R·p + o, applied to every vertex.
template <std::size_t N>
std::array<Vec3, N> transform(const std::array<Vec3, N>& in, double s, const std::array<Vec3, 3>& rot, const Vec3& o) {
  std::array<Vec3, N> out{};
  for (std::size_t k = 0; k < N; ++k) {
    const Vec3 r = apply(rot, in[k]);
    for (std::size_t i = 0; i < 3; ++i) out[k][i] = s * r[i] + o[i];
  }
  return out;
}

const std::array<Vec3, 3> kIdentity = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};

// ---------------------------------------------------------------------------
// Parametric family 1: the disphenoid P1,2 = (±a, 0, h), P3,4 = (0, ±b, −h).
//
// Edges: |P1P2| = 2a, |P3P4| = 2b, and the four "cross" edges all have
//   s = |(a, −b, 2h)| = sqrt(a² + b² + 4h²).
// Volume: from P2, edge vectors (2a,0,0), (a,b,−2h), (a,−b,−2h);
//   det = 2a·(b·(−2h) − (−2h)(−b)) = −8abh, so V = 4abh/3.
// Faces: P1P2P3 has base 2a on the line y = 0, z = h and apex (0,b,−h) at
//   distance sqrt(b² + 4h²): area a·sqrt(b² + 4h²); P1P2P4 the same;
//   P3P4P1 and P3P4P2 by the a↔b mirror: b·sqrt(a² + 4h²) each.
//   A = 2a·sqrt(b² + 4h²) + 2b·sqrt(a² + 4h²).
// Circumcentre: the element is symmetric under x ↦ −x and y ↦ −y, so the
//   centre is (0,0,z) with a² + (h − z)² = b² + (h + z)², i.e.
//   z = (a² − b²)/(4h) and R² = a² + (h − z)².
// L_max = max(2a, 2b, s); ΣL² = 4a² + 4b² + 4s².
// Solid angle at P1 (edges to P2: 2a, to P3, P4: s; opposite edges
//   P2P3 = P2P4 = s, P3P4 = 2b):
//   (2a + s)² − s² = 4a(a + s) twice, and (2s)² − (2b)² = 4(a² + 4h²),
//   so sqrt(Π) = 8a(a + s)·sqrt(a² + 4h²) and with 12V = 16abh:
//   sin(Ω1/2) = 2bh / ((a + s)·sqrt(a² + 4h²)) = sin(Ω2/2);
//   sin(Ω3/2) = sin(Ω4/2) = 2ah / ((b + s)·sqrt(b² + 4h²))  (a ↔ b).
// a = b = 1, h = 1/√2 gives s = 2: the regular tetrahedron of edge 2.
Tet4 disphenoid(double a, double b, double h) { return {{{a, 0, h}, {-a, 0, h}, {0, b, -h}, {0, -b, -h}}}; }

Scores disphenoid_expected(double a, double b, double h) {
  const double s = std::sqrt(a * a + b * b + 4 * h * h);
  const double v = 4 * a * b * h / 3;
  const double area = 2 * a * std::sqrt(b * b + 4 * h * h) + 2 * b * std::sqrt(a * a + 4 * h * h);
  const double r_in = 3 * v / area;
  const double z = (a * a - b * b) / (4 * h);
  const double r_out = std::sqrt(a * a + (h - z) * (h - z));
  const double l_max = std::max({2 * a, 2 * b, s});
  const double sum_l2 = 4 * a * a + 4 * b * b + 4 * s * s;
  const double sin1 = 2 * b * h / ((a + s) * std::sqrt(a * a + 4 * h * h));
  const double sin3 = 2 * a * h / ((b + s) * std::sqrt(b * b + 4 * h * h));
  return {3 * r_in / r_out, 2 * kSqrt6 * r_in / l_max, 12 * std::pow(3 * v, 2.0 / 3.0) / sum_l2,
          1.5 * kSqrt6 * std::min(sin1, sin3)};
}

// ---------------------------------------------------------------------------
// Parametric family 2: a right pyramid over the equilateral triangle of side
// 1 centred at the origin in z = 0 (circumradius ρ = 1/√3, inradius
// 1/(2√3)), apex (0,0,H).
//
// Lateral edges e = sqrt(ρ² + H²) = sqrt(H² + 1/3); base edges 1.
// V = (1/3)·(√3/4)·H = √3·H/12.
// Lateral face: base 1, height sqrt(H² + (1/(2√3))²) = sqrt(H² + 1/12),
//   A = √3/4 + (3/2)·sqrt(H² + 1/12).
// Circumcentre (0,0,c): c² + 1/3 = (H − c)², so c = (H² − 1/3)/(2H) and
//   R = H − c = (H² + 1/3)/(2H).
// L_max = max(1, e); ΣL² = 3·1 + 3e² = 4 + 3H².
// Apex: all three pairs give (e + e)² − 1 = 4e² − 1 = 4H² + 1/3, so
//   sin(Ω_apex/2) = (√3H)/(4H² + 1/3)^(3/2)            (12V = √3H).
// Base vertex: edges 1, 1, e; opposite edges 1, e, e: pairs give
//   (1 + 1)² − 1 = 3 and (1 + e)² − e² = 1 + 2e twice, so
//   sin(Ω_base/2) = √3H / (√3(1 + 2e)) = H/(1 + 2e).
// H = sqrt(2/3) gives e = 1: the regular tetrahedron of edge 1.
// Large H: a needle (three close vertices far from the fourth).
// Small H: a cap (the apex just above the centroid of the opposite face).
Tet4 pyramid(double height) {
  return {{{1 / kSqrt3, 0, 0}, {-0.5 / kSqrt3, 0.5, 0}, {-0.5 / kSqrt3, -0.5, 0}, {0, 0, height}}};
}

Scores pyramid_expected(double height) {
  const double h2 = height * height;
  const double e = std::sqrt(h2 + 1.0 / 3.0);
  const double v = kSqrt3 * height / 12;
  const double area = kSqrt3 / 4 + 1.5 * std::sqrt(h2 + 1.0 / 12.0);
  const double r_in = 3 * v / area;
  const double r_out = (h2 + 1.0 / 3.0) / (2 * height);
  const double l_max = std::max(1.0, e);
  const double sum_l2 = 4 + 3 * h2;
  const double sin_apex = kSqrt3 * height / std::pow(4 * h2 + 1.0 / 3.0, 1.5);
  const double sin_base = height / (1 + 2 * e);
  return {3 * r_in / r_out, 2 * kSqrt6 * r_in / l_max, 12 * std::pow(3 * v, 2.0 / 3.0) / sum_l2,
          1.5 * kSqrt6 * std::min(sin_apex, sin_base)};
}

// Regular tetrahedron of edge 2√2 (alternate corners of the cube [−1,1]³).
const Tet4 kRegular = {{{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}}};
// Equilateral triangle of edge √2.
const Tri3 kEquilateral = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
const Tet4 kCorner = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};

}  // namespace

TEST_CASE("quality: the ideal elements score 1 at every size, position and orientation") {
  const double sizes[] = {1e-6, 1e-3, 1.0, 7.5, 1e6};
  const Vec3 offsets[] = {{0, 0, 0}, {3.5, -2.0, 100.0}};  // in units of the element size
  const std::array<Vec3, 3> rotations[] = {kIdentity, rotation({1, 2, 3}, 0.7), rotation({-2, 0.5, 1}, 2.9)};
  for (double s : sizes)
    for (const Vec3& o : offsets)
      for (const auto& rot : rotations) {
        const Vec3 off = {s * o[0], s * o[1], s * o[2]};
        CAPTURE(s);
        check_scores(transform(kRegular, s, rot, off), {1, 1, 1, 1}, 1e-12);
        const Tri3 t = transform(kEquilateral, s, rot, off);
        CHECK_REL(q::triangle_angle(t[0], t[1], t[2]), 1.0, 1e-12);
        CHECK_REL(q::triangle_edge_ratio(t[0], t[1], t[2]), 1.0, 1e-12);
      }
  // The two parametric families pass through the regular tetrahedron too.
  check_scores(disphenoid(1, 1, 1 / kSqrt2), {1, 1, 1, 1}, 1e-12);
  check_scores(pyramid(std::sqrt(2.0 / 3.0)), {1, 1, 1, 1}, 1e-12);
}

TEST_CASE("quality: right-corner tetrahedron (0,0,0),(1,0,0),(0,1,0),(0,0,1)") {
  // V = 1/6. Faces: three right isosceles triangles of area 1/2 and the
  // equilateral triangle of side √2, area (√3/4)·2 = √3/2; A = (3 + √3)/2.
  // r_in = 3V/A = (1/2)/((3 + √3)/2) = 1/(3 + √3) = (3 − √3)/6 ≈ 0.2113249.
  // Circumcentre (1/2,1/2,1/2) (equidistant from all four), R = √3/2.
  // QT1 = 3·((3 − √3)/6)/(√3/2) = (3 − √3)/√3 = √3 − 1 ≈ 0.7320508.
  // L_max = √2: QT2 = 2√6·(3 − √3)/(6√2) = (3 − √3)/√3 = √3 − 1 as well.
  // ΣL² = 3·1 + 3·2 = 9, 3V = 1/2: QT3 = 12·(1/2)^(2/3)/9 = (4/3)·2^(−2/3)
  //   = (2/3)·2^(1/3) ≈ 0.8399474.
  // Solid angles (12V = 2):
  //   corner: edges 1,1,1, opposite edges √2: each pair (1+1)² − 2 = 2,
  //     sin = 2/sqrt(8) = 1/√2, i.e. Ω = π/2 (an octant, 4π/8).
  //   at (1,0,0): edges to O 1, to B and C √2; opposite OB = OC = 1, BC = √2:
  //     (O,B): (1 + √2)² − 1 = 2 + 2√2, (O,C): the same,
  //     (B,C): (√2 + √2)² − 2 = 6;
  //     sqrt(Π) = sqrt(6·4(1 + √2)²) = 2√6(1 + √2),
  //     sin = 1/(√6(1 + √2)) = (√2 − 1)/√6 ≈ 0.1691019; same at the other two.
  // QT4 = (3√6/2)·(√2 − 1)/√6 = 3(√2 − 1)/2 ≈ 0.6213203.
  const Scores want = {kSqrt3 - 1, kSqrt3 - 1, (2.0 / 3.0) * std::cbrt(2.0), 1.5 * (kSqrt2 - 1)};
  check_scores(kCorner, want, 1e-12);
  // The same values as decimals, worked out from the closed forms above.
  check_scores(kCorner, {0.7320508075688772, 0.7320508075688772, 0.8399473665965822, 0.6213203435596426}, 1e-12);
}

TEST_CASE("quality: sliver (±1,0,h),(0,±1,−h) scores low despite good edges and faces") {
  // Disphenoid with a = b = 1: s = sqrt(2 + 4h²), V = 4h/3, circumcentre at
  // the origin, R = sqrt(1 + h²), each face has area sqrt(1 + 4h²), so
  // r_in = h/sqrt(1 + 4h²); L_max = 2 while h² ≤ 1/2; ΣL² = 16(1 + h²).
  //   QT1 = 3h / (sqrt(1 + 4h²)·sqrt(1 + h²))
  //   QT2 = √6·h / sqrt(1 + 4h²)
  //   QT3 = (3/4)·(4h)^(2/3) / (1 + h²)
  //   QT4 = 3√6·h / ((1 + s)·sqrt(1 + 4h²))        (all vertices alike)
  // h = 0.1: s = sqrt(2.04) ≈ 1.4282857,
  //   QT1 = 0.3/(sqrt(1.04)·sqrt(1.01))      ≈ 0.2927143
  //   QT2 = 0.1√6/sqrt(1.04)                 ≈ 0.2401922
  //   QT3 = 0.75·0.4^(2/3)/1.01              ≈ 0.4031313
  //   QT4 = 0.3√6/((1 + sqrt(2.04))·sqrt(1.04)) ≈ 0.2967430
  for (double h : {0.1, 0.01, 0.3}) {
    CAPTURE(h);
    const double s = std::sqrt(2 + 4 * h * h);
    const double k = std::sqrt(1 + 4 * h * h);
    const Scores want = {3 * h / (k * std::sqrt(1 + h * h)), kSqrt6 * h / k,
                         0.75 * std::pow(4 * h, 2.0 / 3.0) / (1 + h * h), 3 * kSqrt6 * h / ((1 + s) * k)};
    check_scores(disphenoid(1, 1, h), want, 1e-12);
    check_scores(disphenoid(1, 1, h), disphenoid_expected(1, 1, h), 1e-12);
  }
  const Tet4 sliver = disphenoid(1, 1, 0.1);
  check_scores(sliver, {0.29271427209411, 0.24019223070763, 0.40313132919726, 0.29674296412641}, 1e-12);

  // Every face is a near-right isosceles triangle (base 2, legs s, apex angle
  // acos((2s² − 4)/(2s²)) ≈ 88.9°, base angles ≈ 45.6°), and the shortest over
  // the longest edge is s/2 = sqrt(2.04)/2 ≈ 0.714: by its edges and faces
  // the sliver looks fine.
  const double s = std::sqrt(2.04);
  const int faces[4][3] = {{0, 1, 2}, {0, 1, 3}, {2, 3, 0}, {2, 3, 1}};
  for (const auto& f : faces) {
    const Vec3 &a = sliver[f[0]], &b = sliver[f[1]], &c = sliver[f[2]];
    CHECK_REL(q::triangle_edge_ratio(a, b, c), s / 2, 1e-12);
    // θmin = (π − apex)/2 with cos(apex) = (2s² − 4)/(2s²) = 0.08/4.08.
    const double base_angle = (kPi - std::acos(0.08 / 4.08)) / 2;
    CHECK_REL(q::triangle_angle(a, b, c), std::sin(1.5 * base_angle), 1e-12);
    CHECK(q::triangle_angle(a, b, c) > 0.9);
  }
  const Scores sc = scores(sliver);
  CHECK(sc[0] < 0.35);  // QT1
  CHECK(sc[2] < 0.45);  // QT3
  CHECK(sc[3] < 0.35);  // QT4
  // Flatter slivers score lower in every test.
  const Scores flatter = scores(disphenoid(1, 1, 0.01));
  for (std::size_t i = 0; i < 4; ++i) CHECK(flatter[i] < sc[i]);
}

TEST_CASE("quality: wedge and a general disphenoid") {
  // Wedge: one short edge (two nearly coincident vertices) with the other two
  // vertices far apart: a = 0.05, b = 1, h = 1/√2 (a = 1 would be regular).
  // s = sqrt(0.0025 + 1 + 2) = sqrt(3.0025) ≈ 1.7327723, V = 4·0.05·h/3,
  // R from z = (0.0025 − 1)/(4h); the smallest solid angle is at P3 / P4:
  // sin = 2·0.05·h/((1 + s)·√3) ≈ 0.0149; values ≈ (0.13315, 0.11534, 0.20333, 0.05489).
  const double h = 1 / kSqrt2;
  check_scores(disphenoid(0.05, 1, h), disphenoid_expected(0.05, 1, h), 1e-12);
  check_scores(disphenoid(0.05, 1, h), {0.13314539307623, 0.11533935818322, 0.20332716229175, 0.05488931424092},
               1e-11);
  // An asymmetric member whose circumcentre is off the origin:
  // z = (0.09 − 2.89)/1.6 = −1.75.
  check_scores(disphenoid(0.3, 1.7, 0.4), disphenoid_expected(0.3, 1.7, 0.4), 1e-12);
}

TEST_CASE("quality: needle and cap") {
  // Needle: base side 1, apex at H = 10: e = sqrt(100 + 1/3).
  //   QT ≈ (0.16772, 0.13717, 0.10487, 0.0079450); the apex has the smallest
  //   solid angle: sin = 10√3/(400 + 1/3)^(3/2).
  check_scores(pyramid(10), pyramid_expected(10), 1e-12);
  check_scores(pyramid(10), {0.16771817393186, 0.13716936122083, 0.10486762195881, 0.0079450179471869}, 1e-11);
  check_scores(pyramid(100), pyramid_expected(100), 1e-10);
  // Cap: apex 0.01 above the centroid of the base.
  //   R = (1e-4 + 1/3)/0.02 ≈ 16.67 is huge, so QT1 ≈ 9.0e-4 is the lowest;
  //   QT ≈ (0.00089946, 0.024488, 0.079693, 0.017051).
  check_scores(pyramid(0.01), pyramid_expected(0.01), 1e-10);
  check_scores(pyramid(0.01), {0.00089946032378147, 0.024487553364381, 0.079693415682520, 0.017050811665752}, 1e-10);
  // A moderate pyramid for a mid-range check.
  check_scores(pyramid(2), pyramid_expected(2), 1e-12);

  const Scores needle = scores(pyramid(10));
  const Scores cap = scores(pyramid(0.01));
  for (std::size_t i = 0; i < 4; ++i) {
    CHECK(needle[i] < 0.2);
    CHECK(cap[i] < 0.1);
  }
  CHECK(needle[3] < needle[2]);  // the needle's sharp apex dominates QT4
  CHECK(cap[0] < cap[1]);        // the cap's huge circumsphere dominates QT1
}

TEST_CASE("quality: reference triangles") {
  // Right isosceles: angles 45°, 45°, 90°: sin(3·45°/2) = sin(67.5°)
  //   = sqrt(2 + √2)/2 ≈ 0.9238795; legs 1, hypotenuse √2: ratio 1/√2.
  const Vec3 o{0, 0, 0}, x{1, 0, 0}, y{0, 1, 0};
  CHECK_REL(q::triangle_angle(o, x, y), std::sqrt(2 + kSqrt2) / 2, 1e-12);
  CHECK_REL(q::triangle_angle(o, x, y), 0.92387953251128674, 1e-12);
  CHECK_REL(q::triangle_edge_ratio(o, x, y), 1 / kSqrt2, 1e-12);
  // 30-60-90: legs √3 and 1, hypotenuse 2; the angle opposite the leg 1 is
  //   30°: sin(45°) = √2/2; ratio 1/2.
  const Vec3 x3{kSqrt3, 0, 0};
  CHECK_REL(q::triangle_angle(o, x3, y), kSqrt2 / 2, 1e-12);
  CHECK_REL(q::triangle_edge_ratio(o, x3, y), 0.5, 1e-12);
  // Obtuse 30-30-120: base (±√3, 0, 0), apex (0, 1, 0): base angles
  //   atan(1/√3) = 30°, legs 2, base 2√3: angle score √2/2, ratio 1/√3.
  const Vec3 l{-kSqrt3, 0, 0}, r{kSqrt3, 0, 0};
  CHECK_REL(q::triangle_angle(l, r, y), kSqrt2 / 2, 1e-12);
  CHECK_REL(q::triangle_edge_ratio(l, r, y), 1 / kSqrt3, 1e-12);
  // Thin isosceles: base (±1, 0, 0), apex (0, t, 0). The base angles atan(t)
  //   are the smallest (the apex angle is π − 2·atan(t)), so the score is
  //   sin(1.5·atan(t)); the legs sqrt(1 + t²) are shorter than the base 2,
  //   so the ratio is sqrt(1 + t²)/2.
  for (double t : {1e-3, 1e-6}) {
    CAPTURE(t);
    const Vec3 a{-1, 0, 0}, b{1, 0, 0}, c{0, t, 0};
    CHECK_REL(q::triangle_angle(a, b, c), std::sin(1.5 * std::atan(t)), 1e-12);
    CHECK_REL(q::triangle_edge_ratio(a, b, c), std::sqrt(1 + t * t) / 2, 1e-12);
  }
}

TEST_CASE("quality: invariance under translation, scale, rotation, reflection and vertex order") {
  const std::vector<Tet4> tets = {kCorner,
                                  disphenoid(1, 1, 0.1),
                                  disphenoid(0.05, 1, 1 / kSqrt2),
                                  pyramid(10),
                                  pyramid(0.01),
                                  {{{0.1, 0.2, 0.3}, {1.3, -0.4, 0.2}, {0.5, 1.1, -0.7}, {-0.2, 0.3, 0.9}}}};
  const auto rot = rotation({0.3, -1.0, 2.0}, 1.234);
  const std::array<Vec3, 3> mirror = {{{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (const Tet4& t : tets) {
    const Scores base = scores(t);
    const Tet4 variants[] = {transform(t, 1, kIdentity, {12.5, -7.25, 3.0}), transform(t, 1e-6, kIdentity, {0, 0, 0}),
                             transform(t, 1e6, kIdentity, {0, 0, 0}), transform(t, 1, rot, {0, 0, 0}),
                             transform(t, 1, mirror, {0, 0, 0}),  // reversed orientation
                             transform(t, 3.7e-3, rot, {1e-3, 2e-3, -4e-3})};
    for (const Tet4& v : variants) check_scores(v, base, 1e-9);
    std::array<int, 4> perm = {0, 1, 2, 3};
    int count = 0;
    do {
      check_scores({t[perm[0]], t[perm[1]], t[perm[2]], t[perm[3]]}, base, 1e-9);
      ++count;
    } while (std::next_permutation(perm.begin(), perm.end()));
    CHECK(count == 24);
  }

  const std::vector<Tri3> tris = {{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}},
                                  {{{0.1, 0.2, 0.3}, {1.3, -0.4, 0.2}, {0.5, 1.1, -0.7}}},
                                  {{{-1, 0, 0}, {1, 0, 0}, {0, 1e-3, 0}}}};
  for (const Tri3& t : tris) {
    const double angle = q::triangle_angle(t[0], t[1], t[2]);
    const double ratio = q::triangle_edge_ratio(t[0], t[1], t[2]);
    const Tri3 variants[] = {transform(t, 1, kIdentity, {12.5, -7.25, 3.0}), transform(t, 1e-6, kIdentity, {0, 0, 0}),
                             transform(t, 1e6, kIdentity, {0, 0, 0}), transform(t, 1, rot, {0, 0, 0}),
                             transform(t, 1, mirror, {0, 0, 0})};
    for (const Tri3& v : variants) {
      CHECK_REL(q::triangle_angle(v[0], v[1], v[2]), angle, 1e-9);
      CHECK_REL(q::triangle_edge_ratio(v[0], v[1], v[2]), ratio, 1e-9);
    }
    std::array<int, 3> perm = {0, 1, 2};
    do {
      CHECK_REL(q::triangle_angle(t[perm[0]], t[perm[1]], t[perm[2]]), angle, 1e-9);
      CHECK_REL(q::triangle_edge_ratio(t[perm[0]], t[perm[1]], t[perm[2]]), ratio, 1e-9);
    } while (std::next_permutation(perm.begin(), perm.end()));
  }
}

TEST_CASE("quality: degenerate elements score exactly 0, never NaN") {
  auto all_zero = [](const Tet4& t) {
    const Scores sc = scores(t);
    for (double v : sc) {
      CHECK(!std::isnan(v));
      CHECK(v == 0.0);
    }
  };
  SUBCASE("flat tetrahedra") {
    all_zero({{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}});    // four corners of a square
    all_zero({{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}}});    // three of them collinear
    all_zero({{{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}}});    // all four collinear
    all_zero({{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 0}}});  // a cap with height 0
    all_zero(disphenoid(1, 1, 0));                                // a sliver with height 0
    // Points on the tilted plane z = 0.3x − 0.2y + 1, whose coordinates are
    // rounded: coplanar up to rounding, which the tests also count as flat.
    const hmc::Mesh plane = hmc::samples::coplanar(64, 7);
    for (std::size_t i = 0; i + 3 < plane.points.size(); i += 4)
      all_zero({plane.points[i], plane.points[i + 1], plane.points[i + 2], plane.points[i + 3]});
    // Flat at every scale.
    all_zero(transform(Tet4{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}}, 1e-6, rotation({1, 1, 1}, 0.5), {0, 0, 0}));
  }
  SUBCASE("coincident vertices") {
    all_zero({{{0, 0, 0}, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}}});
    const hmc::Mesh dup = hmc::samples::all_duplicates(4);
    all_zero({dup.points[0], dup.points[1], dup.points[2], dup.points[3]});
  }
  SUBCASE("degenerate triangles") {
    const Vec3 o{0, 0, 0}, x{1, 0, 0}, x2{2, 0, 0}, p{0.25, -3.5, 7.0};
    const Tri3 cases[] = {{{o, x, x2}},                    // collinear, distinct: Lmin/Lmax would be 1/2
                          {{x, o, x2}},                    // the same with the 180° angle first
                          {{o, o, x}},                     // two coincident
                          {{p, p, p}},                     // all coincident
                          {{o, {1, 1, 1}, {3, 3, 3}}}};    // collinear off the axes
    for (const Tri3& t : cases) {
      CHECK(q::triangle_angle(t[0], t[1], t[2]) == 0.0);
      CHECK(q::triangle_edge_ratio(t[0], t[1], t[2]) == 0.0);
    }
    // Points on a line with rounded coordinates.
    const hmc::Mesh line = hmc::samples::collinear(30, 3);
    for (std::size_t i = 0; i + 2 < line.points.size(); i += 3) {
      const Vec3 &a = line.points[i], &b = line.points[i + 1], &c = line.points[i + 2];
      CHECK(q::triangle_angle(a, b, c) == 0.0);
      CHECK(q::triangle_edge_ratio(a, b, c) == 0.0);
    }
  }
  SUBCASE("non-finite coordinates") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    for (double bad : {nan, inf}) {
      all_zero({{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, bad}}});
      CHECK(q::triangle_angle({0, 0, 0}, {1, 0, 0}, {bad, 1, 0}) == 0.0);
      CHECK(q::triangle_edge_ratio({0, 0, 0}, {1, 0, 0}, {bad, 1, 0}) == 0.0);
    }
  }
}

TEST_CASE("quality: evaluate() over a small mesh") {
  hmc::Mesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1},          // 0-3: right-corner tetrahedron
              {1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1},   // 4-7: regular tetrahedron
              {kSqrt3, 0, 0},                                     // 8
              {2, 0, 0}};                                         // 9
  m.triangles = {{4, 5, 6},    // equilateral (a face of the regular tet): 1, 1
                 {0, 1, 2},    // right isosceles: sin 67.5°, 1/√2
                 {0, 8, 2},    // 30-60-90: √2/2, 1/2
                 {0, 1, 9},    // collinear: 0, 0
                 {0, 1, 10}};  // index out of range: skipped
  m.tetrahedra = {{4, 5, 6, 7},    // regular: 1, 1, 1, 1
                  {0, 1, 2, 3},    // right corner: √3 − 1, √3 − 1, (2/3)·2^(1/3), 3(√2 − 1)/2
                  {0, 1, 9, 2},    // flat: 0, 0, 0, 0
                  {0, 1, 2, 42}};  // out of range: skipped
  const q::MeshQuality mq = q::evaluate(m);

  using Hist = std::array<std::uint64_t, 10>;
  auto check_stats = [](const q::Stats& s, std::size_t count, double mean, double mn, double mx, const Hist& hist) {
    CHECK(s.count == count);
    CHECK_REL(s.mean, mean, 1e-12);
    CHECK_REL(s.min, mn, 1e-12);
    CHECK_REL(s.max, mx, 1e-12);
    CHECK(s.histogram == hist);
  };
  const double sin675 = std::sqrt(2 + kSqrt2) / 2;  // ≈ 0.924: bin 9
  // Angle scores 1, 0.924, 0.707, 0 → bins 9, 9, 7, 0.
  check_stats(mq.tri_angle, 4, (1 + sin675 + kSqrt2 / 2) / 4, 0, 1, Hist{1, 0, 0, 0, 0, 0, 0, 1, 0, 2});
  // Edge ratios 1, 0.707, 0.5, 0 → bins 9, 7, 5, 0. The equilateral face has
  // all squared edges exactly 8, so its ratio is exactly 1: the histogram
  // below checks that a score of 1 lands in bin 9.
  CHECK(mq.tri_edge.max == 1.0);
  check_stats(mq.tri_edge, 4, (1 + 1 / kSqrt2 + 0.5) / 4, 0, 1, Hist{1, 0, 0, 0, 0, 1, 0, 1, 0, 1});
  // QT1, QT2: 1, 0.732, 0 → bins 9, 7, 0.
  check_stats(mq.qt1, 3, (1 + kSqrt3 - 1) / 3, 0, 1, Hist{1, 0, 0, 0, 0, 0, 0, 1, 0, 1});
  check_stats(mq.qt2, 3, (1 + kSqrt3 - 1) / 3, 0, 1, Hist{1, 0, 0, 0, 0, 0, 0, 1, 0, 1});
  // QT3: 1, 0.840, 0 → bins 9, 8, 0.
  check_stats(mq.qt3, 3, (1 + (2.0 / 3.0) * std::cbrt(2.0)) / 3, 0, 1, Hist{1, 0, 0, 0, 0, 0, 0, 0, 1, 1});
  // QT4: 1, 0.621, 0 → bins 9, 6, 0.
  check_stats(mq.qt4, 3, (1 + 1.5 * (kSqrt2 - 1)) / 3, 0, 1, Hist{1, 0, 0, 0, 0, 0, 1, 0, 0, 1});

  SUBCASE("min and max without degenerate elements") {
    hmc::Mesh good = m;
    good.triangles = {{0, 1, 2}, {0, 8, 2}};
    good.tetrahedra = {{0, 1, 2, 3}};
    const q::MeshQuality g = q::evaluate(good);
    CHECK(g.tri_angle.count == 2);
    CHECK_REL(g.tri_angle.min, kSqrt2 / 2, 1e-12);
    CHECK_REL(g.tri_angle.max, sin675, 1e-12);
    CHECK(g.qt4.count == 1);
    CHECK_REL(g.qt4.mean, 1.5 * (kSqrt2 - 1), 1e-12);
    CHECK(g.qt4.min == g.qt4.max);
  }
  SUBCASE("nothing to score") {
    const Hist zero{};
    hmc::Mesh only_bad;
    only_bad.points = {{0, 0, 0}};
    only_bad.triangles = {{0, 1, 2}};
    only_bad.tetrahedra = {{0, 0, 0, 7}};
    for (const hmc::Mesh& e : {hmc::Mesh{}, hmc::samples::random_ball(10, 1), only_bad}) {
      const q::MeshQuality r = q::evaluate(e);
      for (const q::Stats* s : {&r.tri_angle, &r.tri_edge, &r.qt1, &r.qt2, &r.qt3, &r.qt4}) {
        CHECK(s->count == 0);
        CHECK(s->mean == 0.0);
        CHECK(s->min == 0.0);
        CHECK(s->max == 0.0);
        CHECK(s->histogram == zero);
      }
    }
  }
}
