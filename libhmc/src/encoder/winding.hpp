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
#include <optional>
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
  // A node's moments about its centre while the tree is built: M (first
  // order) and T (second), from which Node's coefficients are folded.
  struct Moments {
    double m[3][3] = {};
    double t[3][3][3] = {};
  };
  std::uint32_t build(std::uint32_t begin, std::uint32_t end, Moments& moments);
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

/// The winding number at q summed over every triangle, without a tree:
/// for a few queries, where building the tree would cost more.
double winding_number(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles, const Vec3& q);

/// A triangle surface closed into a cycle, and the exact jumps of its
/// winding number along segments (encoder side, non-normative). The
/// winding number of a closed surface (every edge used as often in one
/// direction as in the other) is an integer away from it and changes by
/// one where a segment crosses a triangle, up when it enters against the
/// triangle's normal: counting crossings from a point whose value is known
/// gives the value anywhere, exactly, at the cost of a short walk down a
/// box tree instead of a sum over the whole surface. An open surface is
/// closed by caps: each connected part of its border (the edges used more
/// often in one direction than in the other) is cut into closed walks, each
/// closed by halving it (triangles of its own vertices, as small as the arcs
/// they span), so that the surface's winding number is the closed one's
/// less the caps'.
///
/// With a box (a tile's seal box, EncodeOptions::seal_box), a border part
/// whose every vertex lies beyond some face of the box by more than the
/// part's longest edge (per axis), all of them beyond faces of at most one
/// side per axis, is a cut around the box, closed instead by a fan from one apex beyond those faces
/// too (at the part's extreme coordinate there), so that its cap stays
/// outside the box (each cap triangle lies within an edge's length of a
/// segment from the apex to a vertex beyond the same face), and
/// cap_outside() marks its triangles.
///
/// Coordinates are in quarter grid units (4 × grid units; tetrahedron
/// centroids are then integers): the surface's points must be integers in
/// [0, 2^22) in grid units (exact() says whether they are).
class ClosedSurface {
 public:
  using Point = std::array<std::int64_t, 3>;
  ClosedSurface(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles,
                const std::array<std::uint32_t, 6>* box = nullptr);
  /// Whether `points` (grid units) qualify: finite integers in [0, 2^22).
  static bool exact(const std::vector<Vec3>& points);

  /// w(q) − w(p) for the closed surface's winding number w; nothing when
  /// the segment pq touches a triangle other than by crossing its interior
  /// at an interior point of the segment (an end in a triangle, the segment
  /// through an edge or a vertex, or in a triangle's plane across it).
  std::optional<int> jump(const Point& p, const Point& q) const;
  /// A point outside every triangle's bounding box, where w = 0 (`which`
  /// picks one of several, for a retry after a degenerate jump).
  Point outside(int which) const;

  /// The caps' triangles, at cap_points() (grid units); empty when the
  /// surface was closed.
  const std::vector<Vec3>& cap_points() const { return cap_points_; }
  const std::vector<Triangle>& caps() const { return caps_; }
  /// Per cap triangle: 1 when its part is a cut around the box (above).
  const std::vector<std::uint8_t>& cap_outside() const { return cap_outside_; }

 private:
  struct Tri {
    std::array<std::int32_t, 3> a, b, c;  // corners (quarter units)
    std::array<std::int64_t, 3> n;        // (b − a) × (c − a)
  };
  struct Box {
    std::array<std::int32_t, 3> lo, hi;
    std::uint32_t begin = 0, end = 0;   // range in tris_ (leaf) ...
    std::uint32_t left = 0, right = 0;  // ... or children (left != 0)
  };
  std::uint32_t build(std::uint32_t begin, std::uint32_t end);
  static Box bounds(const Tri& t);

  std::vector<Tri> tris_;
  std::vector<Box> boxes_;
  std::vector<Vec3> cap_points_;
  std::vector<Triangle> caps_;
  std::vector<std::uint8_t> cap_outside_;
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
