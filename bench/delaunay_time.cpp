// SPDX-License-Identifier: AGPL-3.0-or-later
// delaunay_time: one canonical Delaunay tetrahedralization, timed; the ratio
// base of bench/compression.py (issue 6: decoding all levels should cost
// little more than one TetGen Delaunay of the finest level).
//
//   delaunay_time [--tetgen-only] LEVEL.points
//
// Reads the grid points of one level in the canonical dump format
// (spec/conformance.md 2.2: one "x y z" line per point, canonical order;
// `hmc dec X.hmc --points-only --canonical DIR` writes DIR/level-0.points),
// runs delaunay() once (TetGen plus the canonical sort, adjacency and
// certificate) -- or, with --tetgen-only, TetGen alone -- and prints one
// JSON line: points, tetrahedra, seconds spent reading and in the
// Delaunay call, and the process' peak resident set (KiB). The harness
// also measures the whole process (os.wait4), like the hmc runs it is
// compared with.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "delaunay/delaunay.hpp"

int main(int argc, char** argv) {
  using namespace hmc;
  using namespace hmc::detail;
  bool tetgen_only = false;
  const char* path = nullptr;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--tetgen-only") == 0) tetgen_only = true;
    else if (!path) path = argv[i];
    else path = nullptr, i = argc;
  }
  if (!path) {
    std::fprintf(stderr, "usage: delaunay_time [--tetgen-only] LEVEL.points\n");
    return 1;
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::FILE* f = std::fopen(path, "r");
  if (!f) {
    std::fprintf(stderr, "delaunay_time: cannot open %s\n", path);
    return 2;
  }
  std::vector<GridPoint> pts;
  unsigned long x, y, z;
  while (std::fscanf(f, "%lu %lu %lu", &x, &y, &z) == 3)
    pts.push_back({static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y), static_cast<std::uint32_t>(z)});
  std::fclose(f);
  const auto t1 = std::chrono::steady_clock::now();
  std::size_t tets = 0;
  bool used = true;
  if (tetgen_only) {
    std::vector<std::array<std::uint32_t, 4>> t, nb;
    used = backend::tetgen(pts, t, nb);
    tets = t.size();
  } else {
    tets = delaunay(pts).tets.size();  // throws StreamError on failure: a bug, exit non-zero
  }
  const auto t2 = std::chrono::steady_clock::now();
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  std::printf("{\"points\": %zu, \"tetrahedra\": %zu, \"mode\": \"%s\", \"tetgen_used\": %s, "
              "\"read_seconds\": %.6f, \"delaunay_seconds\": %.6f, \"peak_rss_kib\": %ld}\n",
              pts.size(), tets, tetgen_only ? "tetgen" : "canonical", used ? "true" : "false",
              std::chrono::duration<double>(t1 - t0).count(), std::chrono::duration<double>(t2 - t1).count(),
              ru.ru_maxrss);
  return 0;
}
