// SPDX-License-Identifier: AGPL-3.0-or-later
// The layer coders of the format (spec 8 and 8A): the first byte of a BASE
// or REFN payload. Declared here once; the layer coders (pointset/) and the
// decoder's dispatch (codec/) use these numbers and nothing else. Every
// other number is bad_layer (BASE 1-4 and REFN 2-6 since spec 0.25, REFN 1
// since 0.27).
#pragma once

#include <cstdint>

namespace hmc::detail {

/// BASE coders (spec 8).
enum class BaseCoder : std::uint8_t {
  octree = 0,  ///< 8.1: one table per depth, no prediction (hmc enc --fast-decode)
  ranked = 5   ///< 8.2: ranked occupancies at the depths that mark it (the default)
};

/// REFN coders (spec 8A).
enum class RefineCoder : std::uint8_t {
  conditional_octree = 0,  ///< 8A.1 with the short header (no ranking fields, no pairing)
  ranked_octree = 7        ///< 8A.1 with the full header (the default)
};

constexpr bool is_base_coder(std::uint8_t c) {
  return c == static_cast<std::uint8_t>(BaseCoder::octree) || c == static_cast<std::uint8_t>(BaseCoder::ranked);
}

/// The exact REFN coders: the conditional octree, either header.
constexpr bool is_octree_refine_coder(std::uint8_t c) {
  return c == static_cast<std::uint8_t>(RefineCoder::conditional_octree) ||
         c == static_cast<std::uint8_t>(RefineCoder::ranked_octree);
}

}  // namespace hmc::detail
