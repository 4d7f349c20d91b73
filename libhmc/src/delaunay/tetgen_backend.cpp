// SPDX-License-Identifier: AGPL-3.0-or-later
// The TetGen 1.5 backend of delaunay(): the only file that includes tetgen.h.
//
// Why TetGen's output is the canonical tetrahedralization (spec/delaunay.md
// §4): TetGen 1.5.0 builds the Delaunay tetrahedralization incrementally
// (Bowyer–Watson) with Shewchuk's exact orient3d/insphere, and breaks
// insphere ties in insphere_s() by the perturbation of spec §3, ranking
// points by their "point mark", which is their position in the input list.
// We pass the points in canonical order, so the mark is the canonical index.
// A point coplanar with a hull face joins that face's hull tet to the cavity
// iff it conflicts with the face's interior tet (the same perturbed test),
// which is the 2D restriction of the same rule. The result is therefore the
// unique regular triangulation of spec §3, independent of TetGen's
// (randomised) insertion order; delaunay() verifies it anyway.
//
// Switches: z (indices from 0), Q (quiet), N and F (no node, face or edge
// output), n (neighbours: neighborlist[4t + k] is the tetrahedron across the
// face opposite corner k, -1 on the hull), J (never renumber points; ours
// are distinct, so nothing would be jettisoned anyway). Default insertion
// order (BRIO with Hilbert curves). No -p/-q/-a/-Y: no Steiner points, no
// refinement. Never -X: exact arithmetic stays on.
//
// The one floating-point hazard. TetGen picks its first tetrahedron with a
// floating-point orient3d (orient3dfast) and a tolerance. With integer
// coordinates whose extent E (largest max - min over the axes) is below
// 2^16, every product in it is below 2^49 and every sum below 2^51, so it is
// exact, and with the default tolerance (-T 1e-8) TetGen accepts exactly the
// truly non-coplanar candidates (|orient| >= 1 > 1e-24 * diagonal^3): its
// first tetrahedron is valid and correctly oriented, and its collinearity
// and coincidence tests (exact cross products, distances >= 1) cannot fail
// on a set that spans 3D. For larger extents the rounding error (up to about
// 2e-15 E^3) could make it accept a coplanar fourth point or the wrong
// orientation; TetGen then fails an assert() and aborts the process.
// Raising the tolerance does not help: TetGen then gives up on thin sets by
// throwing, and TetGen 1.5.0 frees its memory twice when it throws from
// tetrahedralize() in a library build (terminatetetgen() frees, then the
// tetgenmesh destructor frees again), which crashes as well. So TetGen only
// runs when E < 2^16; larger inputs go to the native backend.
#include <tetgen.h>

#include <algorithm>
#include <mutex>

#include "delaunay/delaunay.hpp"
#include "util/error.hpp"

namespace hmc::detail::backend {

namespace {
// TetGen's predicates keep global state (exactinit() sets error bounds and
// static filters from the bounding box of the current input): never run
// two tetrahedralizations at once.
std::mutex tetgen_mutex;
}  // namespace

bool tetgen(const std::vector<GridPoint>& points, std::vector<std::array<std::uint32_t, 4>>& tets,
            std::vector<std::array<std::uint32_t, 4>>& neighbors) {
  std::uint32_t lo[3] = {~0u, ~0u, ~0u}, hi[3] = {0, 0, 0};
  for (const auto& p : points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  if (std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) >= (1u << 16)) return false;
  if (points.size() > 0x7FFFFFFFu / 4) return false;

  char switches[] = "zQNFJn";
  std::lock_guard<std::mutex> lock(tetgen_mutex);
  tetgenio in, out;
  in.firstnumber = 0;
  in.mesh_dim = 3;
  in.numberofpoints = static_cast<int>(points.size());
  in.pointlist = new REAL[3 * points.size()];
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) in.pointlist[3 * i + a] = static_cast<REAL>(points[i][a]);
  try {
    tetrahedralize(switches, &in, &out);
  } catch (int) {
    // terminatetetgen() throws its exit code in library builds. Unreachable
    // for the inputs admitted above (and see the note on double frees).
    return false;
  }
  if (out.numberofcorners != 4 || out.numberoftetrahedra < 0 || out.neighborlist == nullptr) return false;
  const auto nt = static_cast<std::size_t>(out.numberoftetrahedra);
  tets.resize(nt);
  neighbors.resize(nt);
  auto index = [](int v) { return v < 0 ? kNoTet : static_cast<std::uint32_t>(v); };
  for (std::size_t i = 0; i < 4 * nt; ++i) {
    tets[i / 4][i % 4] = index(out.tetrahedronlist[i]);
    neighbors[i / 4][i % 4] = index(out.neighborlist[i]);
  }
  return true;
}

}  // namespace hmc::detail::backend
