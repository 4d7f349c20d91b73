// SPDX-License-Identifier: AGPL-3.0-or-later
//
// hmc/quality.hpp — element quality tests of the thesis (§3.5), normalised so
// that the ideal element (equilateral triangle, regular tetrahedron) scores 1
// and a degenerate element (zero area or volume, coincident vertices) scores
// 0, never NaN. All scores are invariant under translation, uniform scaling,
// rotation and vertex order. Non-normative: these never decide what a decoder
// outputs.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "hmc/mesh.hpp"

namespace hmc::quality {

/// sin(3·θmin/2), θmin the smallest interior angle (thesis Quality_1, §3.5.1).
double triangle_angle(const Vec3& a, const Vec3& b, const Vec3& c) noexcept;
/// Lmin/Lmax, shortest over longest edge (§3.5.2).
double triangle_edge_ratio(const Vec3& a, const Vec3& b, const Vec3& c) noexcept;

/// QT1 = 3·r_in/R_out, radius ratio (§3.5.3).
double tet_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept;
/// QT2 = 2·sqrt(6)·r_in/L_max (§3.5.4).
double tet_inradius_edge(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept;
/// QT3 = 12·(3V)^(2/3) / Σ L_i² over the six edges (§3.5.5).
double tet_volume_edge(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept;
/// QT4 = (3·sqrt(6)/2)·min_i sin(Ω_i/2), Ω_i the solid angle at vertex i, with
/// sin(Ω_i/2) = 12V / sqrt(Π_{j<k; j,k≠i} ((l_ij + l_ik)² − l_jk²)) (§3.5.6).
double tet_min_solid_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept;

/// Summary of one score over a mesh.
struct Stats {
  std::size_t count = 0;  ///< number of elements scored
  double mean = 0;        ///< arithmetic mean (the thesis' Avg_quality)
  double min = 0;
  double max = 0;
  /// histogram[i] counts scores in [i/10, (i+1)/10); a score of exactly 1 counts in bin 9.
  std::array<std::uint64_t, 10> histogram{};
};

/// All six scores of a mesh; triangle scores over Mesh::triangles, tetrahedron
/// scores over Mesh::tetrahedra (a Stats with count 0 where there are none).
struct MeshQuality {
  Stats tri_angle, tri_edge;
  Stats qt1, qt2, qt3, qt4;
};

/// Score every element of `mesh`. Elements with an index out of range are skipped.
MeshQuality evaluate(const Mesh& mesh);

}  // namespace hmc::quality
