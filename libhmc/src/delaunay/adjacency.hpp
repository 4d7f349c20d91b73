// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Face adjacency of a tetrahedralization, and its convex-hull faces.
// Derived from the tetrahedra alone (no backend involved), in linear time.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "delaunay/delaunay.hpp"

namespace hmc::detail {

/// neighbors[t][k] = the tetrahedron sharing local face k of tets[t] (the
/// face opposite tets[t][k]; see kFaceVertices), or kNoTet on the hull.
/// `num_points` bounds the vertex indices. Fails (returns false and sets
/// `error`) when a face is shared by more than two tetrahedra or an index is
/// out of range. Cost: two passes of a counting sort over the 4T faces,
/// bucketed by their smallest vertex (about 0.1 s per million tetrahedra;
/// delaunay() already returns the adjacency, so this is for other callers).
bool build_adjacency(const std::vector<std::array<std::uint32_t, 4>>& tets, std::size_t num_points,
                     std::vector<std::array<std::uint32_t, 4>>& neighbors, std::string* error = nullptr);

/// A convex-hull face: its three vertex indices oriented outward (counter-
/// clockwise seen from outside the hull) and the tetrahedron and local face
/// it belongs to.
struct HullFace {
  std::array<std::uint32_t, 3> v;
  std::uint32_t tet;
  int local_face;
};

/// The hull faces (faces with no neighbour), in order of (tet, local face).
std::vector<HullFace> hull_faces(const std::vector<std::array<std::uint32_t, 4>>& tets,
                                 const std::vector<std::array<std::uint32_t, 4>>& neighbors);

}  // namespace hmc::detail
