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
// face opposite corner k, -1 on the hull; cheaper than rebuilding it), J (never renumber points; ours are
// distinct, so nothing would be jettisoned anyway). No -p/-q/-a/-Y: no
// Steiner points, no refinement. Never -X: exact arithmetic stays on.
// Retries (attempt 1, 2) change only the insertion order: b0 is a plain
// random order, b/1 the input order. They exist because TetGen picks its
// first tetrahedron with a floating-point orient3d and a tolerance, which
// could in principle pick a flat one for coordinates near 2^21.
#include <tetgen.h>

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

bool tetrahedralize(const std::vector<GridPoint>& points, int attempt,
                    std::vector<std::array<std::uint32_t, 4>>& tets,
                    std::vector<std::array<std::uint32_t, 4>>& neighbors) {
  static const char* const kSwitches[] = {"zQNFJn", "zQNFJnb0", "zQNFJnb/1"};
  if (attempt < 0 || attempt >= 3) return false;
  char switches[16] = {};
  for (int i = 0; kSwitches[attempt][i] != '\0'; ++i) switches[i] = kSwitches[attempt][i];

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
  } catch (int code) {
    // terminatetetgen() throws its exit code in library builds:
    // 1 out of memory, 2 internal error, 10 input error (e.g. its tolerance
    // judged the points coplanar).
    if (code == 1) fail(Status::out_of_memory, "TetGen: out of memory");
    tets.clear();
    neighbors.clear();
    return true;  // an empty result fails verification: try the next order
  }
  if (out.numberofcorners != 4 || out.numberoftetrahedra < 0) fail(Status::internal_error, "TetGen: bad output");
  const auto nt = static_cast<std::size_t>(out.numberoftetrahedra);
  tets.resize(nt);
  neighbors.resize(out.neighborlist != nullptr ? nt : 0);
  auto index = [](int v) { return v < 0 ? kNoTet : static_cast<std::uint32_t>(v); };
  for (std::size_t i = 0; i < 4 * nt; ++i) {
    tets[i / 4][i % 4] = index(out.tetrahedronlist[i]);
    if (!neighbors.empty()) neighbors[i / 4][i % 4] = index(out.neighborlist[i]);
  }
  return true;
}

}  // namespace hmc::detail::backend
