// SPDX-License-Identifier: AGPL-3.0-or-later
//
// hmc/mesh.hpp — the in-memory mesh that the encoder takes and the decoder
// and the file readers produce.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace hmc {

/// A point or vector in binary64 coordinates.
using Vec3 = std::array<double, 3>;
/// A triangle: three indices into Mesh::points.
using Triangle = std::array<std::uint32_t, 3>;
/// A tetrahedron: four indices into Mesh::points.
using Tetrahedron = std::array<std::uint32_t, 4>;

/// Vertex positions plus optional connectivity.
///
/// The encoder transmits only the points; it uses the triangles or
/// tetrahedra, when present, to classify the input, measure and tune. A file
/// may carry both (a tetrahedral mesh with its boundary faces, for example).
/// Indices are 0-based and must be below points.size().
struct Mesh {
  std::vector<Vec3> points;
  std::vector<Triangle> triangles;
  std::vector<Tetrahedron> tetrahedra;

  bool empty() const noexcept { return points.empty(); }
};

}  // namespace hmc
