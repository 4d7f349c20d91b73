// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: the mesh and point file readers (the encoder's input, and
// what `hmc enc` opens for a user) on arbitrary bytes. Byte 0 picks the
// reader (PLY, OBJ, OFF, XYZ, STL, MEDIT, Gmsh, legacy VTK); the rest is the
// file. Checks:
//   - a rejected file fails with parse_error or unsupported_format only;
//   - an accepted one has finite points, elements that index them, and no
//     more points or elements than the file has bytes (memory stays
//     proportional to the input);
//   - it survives the library's own writers: written as binary VTK (doubles)
//     and as ASCII MEDIT (17 digits), read back, it is the same mesh, in the
//     same order.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_check.hpp"
#include "hmc/meshio.hpp"
#include "io/common.hpp"
#include "util/error.hpp"

namespace {

using hmc::Mesh;
using Reader = Mesh (*)(const std::string&, std::string_view);

constexpr Reader kReaders[] = {hmc::io::detail::read_ply,   hmc::io::detail::read_obj, hmc::io::detail::read_off,
                               hmc::io::detail::read_xyz,   hmc::io::detail::read_stl, hmc::io::detail::read_medit,
                               hmc::io::detail::read_gmsh,  hmc::io::detail::read_vtk};
constexpr const char* kNames[] = {"ply", "obj", "off", "xyz", "stl", "medit", "gmsh", "vtk"};
constexpr std::size_t kCount = sizeof(kReaders) / sizeof(kReaders[0]);

hmc::Result<Mesh> read(std::size_t which, std::string_view data) {
  return hmc::detail::guarded<hmc::Result<Mesh>>(
      [&]() -> hmc::Result<Mesh> { return kReaders[which](std::string("fuzz.") + kNames[which], data); });
}

bool same_mesh(const Mesh& a, const Mesh& b) {
  return a.points == b.points && a.triangles == b.triangles && a.tetrahedra == b.tetrahedra;
}

// Written with `write` and read back with reader `which`, `m` comes back
// unchanged.
template <class Write>
void check_round_trip(const Mesh& m, Write write, std::size_t which, const char* what) {
  const auto text = hmc::detail::guarded<hmc::Result<std::string>>(
      [&]() -> hmc::Result<std::string> { return write(); });
  FUZZ_CHECK(text.ok(), "%s writer failed: %s", what, text.error().message.c_str());
  const auto back = read(which, text.value());
  FUZZ_CHECK(back.ok(), "%s written mesh not read back: %s", what, back.error().message.c_str());
  FUZZ_CHECK(same_mesh(m, back.value()), "%s round trip changed the mesh (%zu/%zu/%zu -> %zu/%zu/%zu)", what,
             m.points.size(), m.triangles.size(), m.tetrahedra.size(), back.value().points.size(),
             back.value().triangles.size(), back.value().tetrahedra.size());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::size_t which = data[0] % kCount;
  const std::string_view file(reinterpret_cast<const char*>(data + 1), size - 1);
  const auto r = read(which, file);
  if (!r.ok()) {
    const auto s = r.status();
    FUZZ_CHECK(s == hmc::Status::parse_error || s == hmc::Status::unsupported_format, "%s reader: status %d: %s",
               kNames[which], static_cast<int>(s), r.error().message.c_str());
    FUZZ_CHECK(!r.error().message.empty(), "%s reader: an error without a message", kNames[which]);
    return 0;
  }
  const Mesh& m = r.value();
  const std::size_t n = m.points.size();
  FUZZ_CHECK(n <= file.size() && m.triangles.size() <= file.size() && m.tetrahedra.size() <= file.size(),
             "%s reader: %zu points, %zu triangles, %zu tetrahedra from %zu bytes", kNames[which], n,
             m.triangles.size(), m.tetrahedra.size(), file.size());
  for (const auto& p : m.points)
    for (double c : p) FUZZ_CHECK(std::isfinite(c), "%s reader: a non-finite coordinate", kNames[which]);
  for (const auto& t : m.triangles)
    for (auto v : t) FUZZ_CHECK(v < n, "%s reader: triangle corner %u of %zu points", kNames[which], v, n);
  for (const auto& t : m.tetrahedra)
    for (auto v : t) FUZZ_CHECK(v < n, "%s reader: tetrahedron corner %u of %zu points", kNames[which], v, n);

  hmc::io::WriteOptions vtk;
  vtk.binary = true;
  vtk.float32 = false;
  check_round_trip(m, [&] { return hmc::io::detail::write_vtk(m, vtk); }, 7, "binary VTK");
  hmc::io::WriteOptions medit;
  medit.precision = 17;
  check_round_trip(m, [&] { return hmc::io::detail::write_medit(m, medit); }, 5, "MEDIT");
  return 0;
}
