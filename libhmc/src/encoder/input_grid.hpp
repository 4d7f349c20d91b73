// SPDX-License-Identifier: AGPL-3.0-or-later
// The input's connectivity carried to the quantization grid (encoder side):
// what the encoder measures its reconstructions against.
#pragma once

#include <cstdint>
#include <vector>

#include "hmc/codec.hpp"
#include "hmc/mesh.hpp"

namespace hmc::detail {

// Indices into the canonical points; elements whose vertices merged are
// dropped.
struct InputOnGrid {
  std::vector<Triangle> surface;      // triangles, or the boundary of the tetrahedra, facing outward
  std::vector<std::uint32_t> border;  // vertices on border edges of an open surface, ascending
};

/// `quantized[i]`: input point i on the grid; `points`: the distinct grid
/// points in canonical order. Tetrahedra win over triangles (a volume file
/// may also list triangles that are not its boundary); their boundary faces
/// are turned outward by the tetrahedra's orientation in the input's own
/// coordinates, which rounding to the grid can flatten or invert. Triangles
/// are made to agree in orientation across their edges, each connected
/// piece keeping the orientation most of its triangles have.
InputOnGrid input_on_grid(const Mesh& input, const std::vector<GridPoint>& quantized,
                          const std::vector<GridPoint>& points);

}  // namespace hmc::detail
