// SPDX-License-Identifier: AGPL-3.0-or-later
// Shared internals of the mesh file readers and writers: number parsing and
// formatting, field splitting, binary scalar types, and the per-format entry
// points that meshio.cpp dispatches to. Errors are raised with
// hmc::detail::fail and turned into an hmc::Error at the public boundary.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "hmc/mesh.hpp"
#include "hmc/meshio.hpp"
#include "util/error.hpp"

namespace hmc::io::detail {

// ---------------------------------------------------------------- text ----

inline bool is_space(char c) noexcept {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

/// ASCII case-insensitive comparison.
bool iequals(std::string_view a, std::string_view b) noexcept;
bool istarts_with(std::string_view s, std::string_view prefix) noexcept;
std::string_view trim(std::string_view s) noexcept;
std::string to_lower(std::string_view s);

/// A token as it should appear in an error message: quoted, shortened, with
/// non-printable bytes escaped (the input may be arbitrary binary data).
std::string quote(std::string_view s);

/// Parses the whole of `s` as a decimal floating-point number (a leading '+'
/// is allowed). Overflow yields an infinity and underflow a zero, so that the
/// caller's finiteness check reports the former. False if `s` is not a number.
bool parse_double(std::string_view s, double& out) noexcept;
/// Parses the whole of `s` as a decimal integer (a leading '+' is allowed).
bool parse_int(std::string_view s, std::int64_t& out) noexcept;

/// Whitespace-separated fields of one line. A `comment` character (if not
/// '\0') ends the line; with `commas`, ',' and ';' also separate fields.
class Fields {
 public:
  Fields() = default;
  explicit Fields(std::string_view line, char comment = '\0', bool commas = false) noexcept
      : s_(line), comment_(comment), commas_(commas) {}

  bool next(std::string_view& field) noexcept {
    skip_separators();
    if (i_ >= s_.size() || is_comment(s_[i_])) {
      i_ = s_.size();
      return false;
    }
    const std::size_t begin = i_;
    while (i_ < s_.size() && !is_separator(s_[i_]) && !is_comment(s_[i_])) ++i_;
    field = s_.substr(begin, i_ - begin);
    return true;
  }

  /// True when no field is left.
  bool done() noexcept {
    skip_separators();
    return i_ >= s_.size() || is_comment(s_[i_]);
  }

 private:
  bool is_comment(char c) const noexcept { return comment_ != '\0' && c == comment_; }
  bool is_separator(char c) const noexcept { return is_space(c) || (commas_ && (c == ',' || c == ';')); }
  void skip_separators() noexcept {
    while (i_ < s_.size() && is_separator(s_[i_])) ++i_;
  }

  std::string_view s_;
  std::size_t i_ = 0;
  char comment_ = '\0';
  bool commas_ = false;
};

// -------------------------------------------------------------- binary ----

/// Binary scalar types shared by PLY, VTK and Gmsh.
enum class Scalar : std::uint8_t { i8, u8, i16, u16, i32, u32, i64, u64, f32, f64 };

std::size_t scalar_size(Scalar t) noexcept;
bool scalar_is_integer(Scalar t) noexcept;

/// Assembles an unsigned integer from bytes in the given byte order; no
/// casted-pointer reads, so any alignment is fine.
template <class U>
U load_uint(const unsigned char* p, bool big_endian) noexcept {
  U v = 0;
  for (std::size_t i = 0; i < sizeof(U); ++i) {
    const std::size_t k = big_endian ? i : sizeof(U) - 1 - i;
    v = static_cast<U>((static_cast<std::uint64_t>(v) << 8) | p[k]);
  }
  return v;
}

// -------------------------------------------------------------- output ----

void append_uint(std::string& out, std::uint64_t v);
/// `precision` significant digits; 17 or more gives the shortest text that
/// reads back to exactly the same binary64.
void append_real(std::string& out, double v, int precision);

template <class U>
void append_bytes(std::string& out, U v, bool big_endian) {
  char b[sizeof(U)];
  for (std::size_t i = 0; i < sizeof(U); ++i) {
    const auto byte = static_cast<char>(static_cast<unsigned char>(static_cast<std::uint64_t>(v) >> (8 * i)));
    b[big_endian ? sizeof(U) - 1 - i : i] = byte;
  }
  out.append(b, sizeof(U));
}
/// Append `prefix`, then "x y z" as append_real writes them, and a newline.
void append_point_line(std::string& out, const char* prefix, const Vec3& p, int precision);
/// Append the coordinates of every point, x y z, as binary64 or (float32)
/// rounded to binary32, in one resize of `out`.
void append_points(std::string& out, const std::vector<Vec3>& points, bool float32, bool big_endian);

// ---------------------------------------------------------- mesh build ----

/// Appends the fan triangulation (c0, ci, ci+1) of a polygon with n >= 3
/// corners.
void add_fan(Mesh& mesh, const std::uint32_t* corners, std::size_t n);

/// Indices that were read in the order the file gave them and must be checked
/// against the vertex count only once it is known (OBJ vertices may follow
/// faces; MEDIT sections come in any order). Remembers the largest index and
/// where it was seen.
struct MaxIndex {
  std::uint64_t value = 0;
  std::size_t line = 0;
  bool any = false;
  void see(std::uint64_t v, std::size_t at_line) noexcept {
    if (!any || v > value) {
      value = v;
      line = at_line;
      any = true;
    }
  }
};

// ------------------------------------------------------------- formats ----

/// Reads a whole file; raises io_error.
std::string load_file(const std::string& path, std::uint64_t max_bytes = (1ull << 34));

Mesh read_ply(const std::string& name, std::string_view data);
Mesh read_obj(const std::string& name, std::string_view data);
Mesh read_off(const std::string& name, std::string_view data);
Mesh read_xyz(const std::string& name, std::string_view data);
Mesh read_stl(const std::string& name, std::string_view data);
Mesh read_medit(const std::string& name, std::string_view data);
Mesh read_gmsh(const std::string& name, std::string_view data);
Mesh read_vtk(const std::string& name, std::string_view data);
/// `path` names the .node, .ele or .face file or the common stem.
Mesh read_tetgen(const std::string& path);

/// Paths of the TetGen files for a stem-or-file path.
struct TetgenPaths {
  std::string node, ele, face;
};
TetgenPaths tetgen_paths(const std::string& path);

std::string write_ply(const Mesh& mesh, const WriteOptions& opt);
std::string write_obj(const Mesh& mesh, const WriteOptions& opt);
std::string write_xyz(const Mesh& mesh, const WriteOptions& opt);
std::string write_vtk(const Mesh& mesh, const WriteOptions& opt);
std::string write_vtu(const Mesh& mesh, const WriteOptions& opt);
std::string write_medit(const Mesh& mesh, const WriteOptions& opt);
/// The .node, .ele (empty string if no tetrahedra) and .face (empty if no
/// triangles) contents.
struct TetgenFiles {
  std::string node, ele, face;
};
TetgenFiles write_tetgen(const Mesh& mesh, const WriteOptions& opt);

}  // namespace hmc::io::detail
