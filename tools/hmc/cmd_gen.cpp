// SPDX-License-Identifier: AGPL-3.0-or-later
#include <cmath>
#include <cstdio>
#include <string>

#include "cli.hpp"
#include "hmc/meshio.hpp"
#include "samples.hpp"

namespace hmc::cli {

int cmd_gen(int argc, char** argv) {
  Args a(argc, argv, 2, {"--ascii"}, {"-o", "--output", "--vertices", "--seed"});
  const auto n = static_cast<double>(a.get_int("--vertices", 36450, 1, 100000000));
  const auto seed = static_cast<std::uint64_t>(a.get_int("--seed", 1, 0, 1ll << 62));
  const std::string out = a.has("-o") ? a.get("-o") : a.get("--output");
  if (!a.ok() || a.positional().size() != 1 || out.empty()) {
    std::fprintf(stderr,
                 "hmc gen: %s\nusage: hmc gen torus|sphere|ball|lattice [--vertices N] [--seed S] -o OUT\n"
                 "  torus    closed triangle surface of genus 1 on a 2:1 grid (default 36450 = 270 x 135)\n"
                 "  sphere   closed triangle surface (UV sphere)\n"
                 "  ball     random points inside a ball (no connectivity)\n"
                 "  shells   a ball sampled on concentric shells (the thesis' 587-vertex sphere; points only)\n"
                 "  lattice  cubic lattice of points (many cospherical quadruples)\n",
                 a.ok() ? "need a sample name and -o OUT" : a.error().c_str());
    return kUsage;
  }
  const std::string what = a.positional()[0];
  Mesh m;
  if (what == "torus") {
    const int nv = std::max(3, static_cast<int>(std::lround(std::sqrt(n / 2))));
    const int nu = std::max(3, static_cast<int>(std::lround(n / nv)));
    m = samples::torus(nu, nv);
  } else if (what == "sphere") {
    const int rings = std::max(2, static_cast<int>(std::lround(std::sqrt(n / 2))));
    m = samples::uv_sphere(rings, 2 * rings);
  } else if (what == "ball") {
    m = samples::random_ball(static_cast<std::size_t>(n), seed);
  } else if (what == "shells") {
    // The thesis' 587-vertex sphere (table 4.7: 247 boundary vertices, then
    // layers of 171, 110, 53 and 6), scaled to about `n` vertices.
    const double f = n / 587.0;
    std::vector<int> counts;
    for (int c : {247, 171, 110, 53, 6}) counts.push_back(std::max(1, static_cast<int>(std::lround(c * f))));
    m = samples::layered_ball(counts);
  } else if (what == "lattice") {
    const int k = std::max(1, static_cast<int>(std::lround(std::cbrt(n))));
    m = samples::lattice(k, k, k);
  } else {
    std::fprintf(stderr, "hmc gen: unknown sample '%s' (torus, sphere, ball, shells, lattice)\n", what.c_str());
    return kUsage;
  }
  io::WriteOptions wo;
  wo.binary = !a.flag("--ascii");
  auto w = io::write_mesh(out, m, io::Format::automatic, wo);
  if (!w) return report("cannot write " + out, w.error(), Stage::output);
  std::printf("%s: %s, %zu vertices, %zu triangles\n", out.c_str(), what.c_str(), m.points.size(), m.triangles.size());
  return kOk;
}

}  // namespace hmc::cli
