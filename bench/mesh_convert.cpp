// SPDX-License-Identifier: AGPL-3.0-or-later
// mesh_convert: hand a shared model to Draco (bench/compression.py).
//
//   mesh_convert [--points] IN OUT.obj
//
// Reads IN with hmc's readers (any format hmc enc takes) and writes its
// vertex positions, exactly (17 significant digits), and its triangles, if
// any, as OBJ: no normals, texture coordinates or tetrahedra, so Draco codes
// the same positions HMC codes and nothing else. --points drops the
// triangles too: Draco's point-cloud mode, given an OBJ with faces, keeps
// only the vertices the faces use (a volume's boundary). Prints
// "points triangles" of the input.
#include <cstdio>
#include <cstring>

#include "hmc/meshio.hpp"

int main(int argc, char** argv) {
  const bool points_only = argc == 4 && std::strcmp(argv[1], "--points") == 0;
  if (argc != 3 + (points_only ? 1 : 0)) {
    std::fprintf(stderr, "usage: mesh_convert [--points] IN OUT.obj\n");
    return 1;
  }
  const char* in = argv[argc - 2];
  const char* out = argv[argc - 1];
  auto mesh = hmc::io::read_mesh(in);
  if (!mesh) {
    std::fprintf(stderr, "mesh_convert: %s\n", mesh.error().to_string().c_str());
    return 2;
  }
  hmc::Mesh m = std::move(mesh.value());
  const std::size_t triangles = m.triangles.size();
  m.tetrahedra.clear();
  if (points_only) m.triangles.clear();
  hmc::io::WriteOptions wo;
  wo.protect_path = in;
  auto w = hmc::io::write_mesh(out, m, hmc::io::Format::obj, wo);
  if (!w) {
    std::fprintf(stderr, "mesh_convert: %s\n", w.error().to_string().c_str());
    return 4;
  }
  std::printf("%zu %zu\n", m.points.size(), triangles);
  return 0;
}
