// SPDX-License-Identifier: AGPL-3.0-or-later
// Morton (z-order) keys of grid points: the octree coders' node order, and
// a space-filling order for anything that walks points or cells in batches
// (Delaunay insertion, winding-number queries).
#pragma once

#include <cstdint>

#include "hmc/codec.hpp"

namespace hmc::detail {

/// Morton key of a point: bits interleaved x, y, z from the most significant
/// of the low q bits down, so that the 3-bit group at depth d is the child
/// index (x_bit << 2) | (y_bit << 1) | z_bit. Bits at or above q are ignored.
inline std::uint64_t morton_key(const GridPoint& p, int q) {
  std::uint64_t key = 0;
  for (int b = q - 1; b >= 0; --b)
    key = (key << 3) | (((p[0] >> b) & 1u) << 2) | (((p[1] >> b) & 1u) << 1) | ((p[2] >> b) & 1u);
  return key;
}

}  // namespace hmc::detail
