// SPDX-License-Identifier: AGPL-3.0-or-later
// The TetGen backend of a build without TetGen (HMC_WITH_TETGEN=OFF, e.g.
// WebAssembly): never applicable, so delaunay() always takes the native
// exact backend, whose output is the same canonical tetrahedralization
// (spec/delaunay.md), verified the same way.
#include "delaunay/delaunay.hpp"

namespace hmc::detail::backend {

bool tetgen(const std::vector<GridPoint>&, std::vector<std::array<std::uint32_t, 4>>&,
            std::vector<std::array<std::uint32_t, 4>>&) {
  return false;
}

}  // namespace hmc::detail::backend
