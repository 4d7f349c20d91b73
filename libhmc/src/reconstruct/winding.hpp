// SPDX-License-Identifier: AGPL-3.0-or-later
// Generalized winding numbers of query points with respect to a triangle
// soup (encoder side, non-normative): the encoder uses them to tell which
// Delaunay tetrahedra lie inside the input surface or volume. Far clusters
// of triangles are replaced by a second-order expansion of their solid
// angle around their area-weighted centroid, near ones summed exactly, so
// a query costs O(log F) for F triangles.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hmc/mesh.hpp"

namespace hmc::detail {

class WindingNumber {
 public:
  /// `triangles` index `points`; orientation gives the sign (counter-
  /// clockwise seen from outside: +1 inside a closed surface). `points`
  /// must outlive this object (the tree keeps only the triangles' indices).
  WindingNumber(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles);
  /// Winding number at q (1 inside, 0 outside a closed oriented surface).
  double operator()(const Vec3& q) const;

 private:
  struct Node {
    Vec3 centre{};           // area-weighted centroid
    Vec3 area{};             // sum of area vectors (half cross products)
    // Moments of the triangles' area about the centre, folded into the
    // coefficients the far-field expansion contracts with (see build()):
    // first order, trace and the quadratic form's six coefficients; second
    // order, two vectors and the cubic form's ten coefficients.
    double trace1 = 0;
    std::array<double, 6> quad1{};
    Vec3 u2{}, v2{};
    std::array<double, 10> cubic2{};
    double radius = 0;       // bounds every triangle vertex around centre
    std::uint32_t begin = 0, end = 0;  // range in tri_ (leaf) ...
    std::uint32_t left = 0, right = 0; // ... or children (left != 0)
  };
  std::uint32_t build(std::uint32_t begin, std::uint32_t end);
  double query(std::uint32_t node, const Vec3& q) const;

  std::array<Vec3, 3> corners(std::uint32_t i) const {
    const auto& t = tri_[i];
    return {points_[t[0]], points_[t[1]], points_[t[2]]};
  }

  const std::vector<Vec3>& points_;
  std::vector<Triangle> tri_;             // in tree order once built
  std::vector<std::uint32_t> order_;      // tri_ indices in tree order, while building
  std::vector<Node> nodes_;
};

/// Oriented boundary faces of a tetrahedral mesh (faces used by exactly one
/// tetrahedron), counter-clockwise seen from outside whatever the
/// orientation of the tetrahedra.
std::vector<Triangle> boundary_faces(const std::vector<Vec3>& points, const std::vector<Tetrahedron>& tets);

/// Swap t's last two vertices unless it is positively oriented at `points`.
void orient_positive(const std::vector<Vec3>& points, Tetrahedron& t);

/// The same for tetrahedra whose orientation is known to be positive
/// (orient3d > 0 in whatever coordinates they were oriented in).
std::vector<Triangle> boundary_faces(const std::vector<Tetrahedron>& positive);

}  // namespace hmc::detail
