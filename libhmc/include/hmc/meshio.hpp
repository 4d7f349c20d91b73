// SPDX-License-Identifier: AGPL-3.0-or-later
//
// hmc/meshio.hpp — reading and writing the mesh and point file formats that
// HMC users already have.
//
// Readers: PLY (ascii, binary little- and big-endian), OBJ, OFF, XYZ, STL
// (ascii and binary), TetGen .node/.ele, MEDIT .mesh, Gmsh .msh (2.2 and 4.1,
// ascii and binary), VTK legacy unstructured grid (ascii and binary).
// Writers: PLY, OBJ, XYZ, VTK legacy, VTU (ParaView XML), MEDIT and TetGen.
//
// Every reader rejects malformed files with Status::parse_error and a message
// naming the file and the line (text formats) or byte offset (binary
// formats) and what was wrong, and rejects NaN and infinite coordinates.
// Every writer is atomic: it writes a temporary file beside the target and
// renames it into place, so a failed write leaves no partial file and an
// existing file of the same name is untouched.
#pragma once

#include <string>
#include <string_view>

#include "hmc/mesh.hpp"
#include "hmc/status.hpp"

namespace hmc::io {

/// A file format. `automatic` picks the format from the file extension
/// (and, for reading, from the first bytes where the extension is ambiguous).
enum class Format {
  automatic,
  ply,     ///< .ply
  obj,     ///< .obj
  off,     ///< .off
  xyz,     ///< .xyz, .pts, .txt: one "x y z" per line
  stl,     ///< .stl
  tetgen,  ///< .node, with .ele (tetrahedra) and/or .face beside it
  medit,   ///< .mesh
  gmsh,    ///< .msh
  vtk,     ///< .vtk legacy unstructured grid
  vtu,     ///< .vtu XML unstructured grid (write only)
};

/// Lower-case name of a format ("ply", "tetgen", ...).
const char* format_name(Format f) noexcept;

/// The format a path's extension names, or Format::automatic if unknown.
Format format_from_path(std::string_view path) noexcept;

/// Read a mesh. For TetGen, `path` may name the .node or the .ele file; the
/// other is found beside it. Polygons with more than three corners (OBJ, OFF,
/// PLY) are fan-triangulated. Only points, triangles and tetrahedra are kept;
/// other element types (edges, quads in volume files, hexahedra) are skipped.
Result<Mesh> read_mesh(const std::string& path, Format format = Format::automatic);

/// Options for writing.
struct WriteOptions {
  bool binary = true;        ///< PLY, VTK: binary (little-endian PLY) or ascii
  int precision = 17;        ///< significant digits for ascii coordinates (17 or more: shortest exact text)
  /// Binary PLY and VTK: coordinates as 32-bit floats (half the bytes, about
  /// 7 significant digits) instead of 64-bit doubles. Other formats ignore it.
  bool float32 = false;
  /// When set, refuse (invalid_argument) to write over this file: a command
  /// passes its input path so it can never overwrite what it reads.
  std::string protect_path;
};

/// Write a mesh. Surfaces (triangles) go to PLY, OBJ, VTK, VTU; tetrahedra to
/// VTK, VTU, MEDIT and TetGen (.node plus .ele, and .face when triangles are
/// present); XYZ writes points only. For TetGen, `path` names the .node file.
/// Atomic: nothing is left behind on failure.
Result<Done> write_mesh(const std::string& path, const Mesh& mesh,
                        Format format = Format::automatic,
                        const WriteOptions& options = {});

/// Write `bytes` to `path` atomically (temporary file in the same directory,
/// fsync, rename). Refuses to write over `protect_path` when it names the same
/// file (used to stop a command from overwriting its own input).
Result<Done> write_file_atomic(const std::string& path, std::string_view bytes,
                               const std::string& protect_path = {});

/// Read a whole file into memory, with a size cap.
Result<std::string> read_file(const std::string& path,
                              std::uint64_t max_bytes = (1ull << 34));

}  // namespace hmc::io
