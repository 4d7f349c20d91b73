// SPDX-License-Identifier: AGPL-3.0-or-later
// VTK legacy files (ascii and big-endian binary; UNSTRUCTURED_GRID and
// POLYDATA, classic and 5.1 cell layouts), and the VTU XML writer.
#include <cmath>
#include <limits>
#include <vector>

#include "io/common.hpp"
#include "io/input.hpp"

namespace hmc::io::detail {

namespace {

constexpr std::uint64_t kMaxPoints = std::numeric_limits<std::uint32_t>::max();
constexpr std::int64_t kVtkTriangle = 5;
constexpr std::int64_t kVtkTetra = 10;

bool vtk_scalar(std::string_view name, Scalar& t) noexcept {
  struct Entry {
    const char* name;
    Scalar type;
  };
  static const Entry table[] = {
      {"unsigned_char", Scalar::u8},   {"char", Scalar::i8},           {"signed_char", Scalar::i8},
      {"unsigned_short", Scalar::u16}, {"short", Scalar::i16},         {"unsigned_int", Scalar::u32},
      {"int", Scalar::i32},            {"unsigned_long", Scalar::u64}, {"long", Scalar::i64},
      {"float", Scalar::f32},          {"double", Scalar::f64},        {"vtktypeint8", Scalar::i8},
      {"vtktypeuint8", Scalar::u8},    {"vtktypeint16", Scalar::i16},  {"vtktypeuint16", Scalar::u16},
      {"vtktypeint32", Scalar::i32},   {"vtktypeuint32", Scalar::u32}, {"vtktypeint64", Scalar::i64},
      {"vtktypeuint64", Scalar::u64},  {"vtktypefloat32", Scalar::f32}, {"vtktypefloat64", Scalar::f64},
      {"vtkidtype", Scalar::i64},
  };
  for (const Entry& e : table)
    if (iequals(name, e.name)) {
      t = e.type;
      return true;
    }
  return false;
}

// A cell list in one layout: cell i is conn[offsets[i] .. offsets[i+1]).
struct CellList {
  std::vector<std::int64_t> offsets{0};
  std::vector<std::int64_t> conn;
  std::size_t where = 0;  // line (ascii) or byte offset (binary) of its keyword
  bool present = false;
  std::size_t count() const noexcept { return offsets.size() - 1; }
};

class Reader {
 public:
  Reader(const std::string& name, std::string_view data) : in_(name, data) {}

  Mesh run() {
    read_header();
    std::string_view tok;
    while (in_.next_token(tok)) {
      if (iequals(tok, "POINTS")) {
        read_points();
      } else if (iequals(tok, "CELLS") && !polydata_) {
        if (cells_.present) in_.fail("second CELLS section");
        cells_ = read_cells("CELLS");
      } else if (iequals(tok, "CELL_TYPES") && !polydata_) {
        read_types();
      } else if (polydata_ && (iequals(tok, "POLYGONS") || iequals(tok, "TRIANGLE_STRIPS") ||
                               iequals(tok, "VERTICES") || iequals(tok, "LINES"))) {
        const bool polygons = iequals(tok, "POLYGONS"), strips = iequals(tok, "TRIANGLE_STRIPS");
        const CellList list = read_cells(tok);
        if (polygons || strips) add_polydata(list, strips);
      } else if (iequals(tok, "FIELD")) {
        skip_field();
      } else if (iequals(tok, "METADATA")) {
        skip_metadata();
      } else if (iequals(tok, "POINT_DATA") || iequals(tok, "CELL_DATA")) {
        break;  // attributes follow; the geometry is complete
      } else {
        in_.fail("unknown or misplaced keyword " + quote(tok));
      }
    }
    if (!have_points_) in_.fail("missing POINTS section");
    if (cells_.present != have_types_)
      in_.fail(cells_.present ? "CELLS without CELL_TYPES" : "CELL_TYPES without CELLS");
    if (cells_.present) add_grid_cells();
    return std::move(mesh_);
  }

 private:
  void read_header() {
    std::string_view line;
    if (!in_.next_line(line) || !istarts_with(trim(line), "# vtk DataFile Version"))
      in_.fail("not a VTK legacy file (missing '# vtk DataFile Version' header)");
    if (!in_.next_line(line)) in_.fail("unexpected end of file, expected the title line");
    if (!in_.next_line(line)) in_.fail("unexpected end of file, expected ASCII or BINARY");
    line = trim(line);
    if (iequals(line, "BINARY")) binary_ = true;
    else if (!iequals(line, "ASCII")) in_.fail("expected ASCII or BINARY, found " + quote(line));
    in_.set_binary(binary_);
    in_.expect_keyword("DATASET");
    const std::string_view type = in_.token("dataset type");
    if (iequals(type, "POLYDATA")) {
      polydata_ = true;
    } else if (!iequals(type, "UNSTRUCTURED_GRID")) {
      hmc::detail::fail(Status::unsupported_format,
                        in_.name() + ": VTK dataset " + quote(type) + " is not supported (only UNSTRUCTURED_GRID and POLYDATA)");
    }
  }

  Scalar data_type(std::string_view what) {
    const std::string_view name = in_.token(what);
    Scalar t;
    if (!vtk_scalar(name, t)) in_.fail("unsupported data type " + quote(name) + " for " + std::string(what));
    return t;
  }

  double real(Scalar t, const char* what) {
    if (!binary_) return in_.real(in_.token(what), what);
    const double v = in_.read_scalar(t, true, what);
    if (!std::isfinite(v)) in_.fail(std::string("non-finite ") + what);
    return v;
  }

  std::int64_t integer(Scalar t, const char* what) {
    if (!binary_) return in_.integer(in_.token(what), what);
    return in_.read_integer(t, true, what);
  }

  void begin_data(std::uint64_t values, Scalar t, std::string_view what) {
    if (binary_) {
      in_.end_header_line(what);
      in_.check_binary_count(values, scalar_size(t), what);
    } else {
      in_.check_text_count(values, 1, what);
    }
  }

  void read_points() {
    if (have_points_) in_.fail("second POINTS section");
    have_points_ = true;
    const std::uint64_t n = in_.count(in_.token("point count"), "point count");
    const Scalar t = data_type("POINTS");
    if (n > kMaxPoints) in_.fail("too many points (" + std::to_string(n) + ")");
    begin_data(3 * n, t, "POINTS");
    mesh_.points.reserve(static_cast<std::size_t>(n));
    for (std::uint64_t i = 0; i < n; ++i) {
      Vec3 p;
      p[0] = real(t, "x coordinate");
      p[1] = real(t, "y coordinate");
      p[2] = real(t, "z coordinate");
      mesh_.points.push_back(p);
    }
  }

  CellList read_cells(std::string_view keyword) {
    if (!have_points_) in_.fail(std::string(keyword) + " before POINTS");
    CellList list;
    list.present = true;
    list.where = binary_ ? in_.mark() : in_.line();
    const std::uint64_t n = in_.count(in_.token("cell count"), "cell count");
    const std::uint64_t size = in_.count(in_.token("cell list size"), "cell list size");
    // The 5.1 layout follows the counts with OFFSETS and CONNECTIVITY arrays.
    bool modern = false;
    if (binary_) {
      in_.end_header_line(keyword);
      modern = istarts_with(in_.rest(), "OFFSETS");
    } else {
      const Input::State s = in_.save();
      std::string_view tok;
      modern = in_.next_token(tok) && iequals(tok, "OFFSETS");
      in_.restore(s);
    }
    if (modern) {
      read_modern_cells(list, n, size);
      return list;
    }
    const Scalar t = Scalar::i32;
    if (n > size) in_.fail(std::string(keyword) + " declares " + std::to_string(n) + " cells in only " +
                           std::to_string(size) + " values");
    if (binary_) in_.check_binary_count(size, 4, keyword);
    else in_.check_text_count(size, 1, keyword);
    list.offsets.reserve(static_cast<std::size_t>(n) + 1);
    list.conn.reserve(static_cast<std::size_t>(size - n));
    std::uint64_t used = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::int64_t k = integer(t, "cell point count");
      if (k < 0 || used >= size || static_cast<std::uint64_t>(k) > size - used - 1)
        in_.fail("cell " + std::to_string(i) + " point count " + std::to_string(k) + " overruns the declared size " +
                 std::to_string(size) + " of " + std::string(keyword));
      used += 1 + static_cast<std::uint64_t>(k);
      for (std::int64_t j = 0; j < k; ++j) list.conn.push_back(integer(t, "cell point index"));
      list.offsets.push_back(static_cast<std::int64_t>(list.conn.size()));
    }
    if (used != size)
      in_.fail(std::string(keyword) + " declares size " + std::to_string(size) + " but its cells use " +
               std::to_string(used) + " values");
    return list;
  }

  void read_modern_cells(CellList& list, std::uint64_t noffsets, std::uint64_t nconn) {
    in_.expect_keyword("OFFSETS");
    Scalar t = data_type("OFFSETS");
    if (!scalar_is_integer(t)) in_.fail("OFFSETS must have an integer type");
    begin_data(noffsets, t, "OFFSETS");
    list.offsets.clear();
    list.offsets.reserve(static_cast<std::size_t>(noffsets));
    for (std::uint64_t i = 0; i < noffsets; ++i) {
      const std::int64_t o = integer(t, "cell offset");
      const std::int64_t prev = list.offsets.empty() ? 0 : list.offsets.back();
      if ((i == 0 && o != 0) || o < prev || static_cast<std::uint64_t>(o) > nconn)
        in_.fail("bad cell offset " + std::to_string(o) + " (offsets must start at 0, not decrease and not exceed " +
                 std::to_string(nconn) + ")");
      list.offsets.push_back(o);
    }
    if (list.offsets.empty()) list.offsets.push_back(0);
    if (static_cast<std::uint64_t>(list.offsets.back()) != nconn)
      in_.fail("the last cell offset " + std::to_string(list.offsets.back()) + " differs from the connectivity size " +
               std::to_string(nconn));
    in_.expect_keyword("CONNECTIVITY");
    t = data_type("CONNECTIVITY");
    if (!scalar_is_integer(t)) in_.fail("CONNECTIVITY must have an integer type");
    begin_data(nconn, t, "CONNECTIVITY");
    list.conn.reserve(static_cast<std::size_t>(nconn));
    for (std::uint64_t i = 0; i < nconn; ++i) list.conn.push_back(integer(t, "cell point index"));
  }

  void read_types() {
    if (have_types_) in_.fail("second CELL_TYPES section");
    have_types_ = true;
    types_where_ = binary_ ? in_.mark() : in_.line();
    const std::uint64_t n = in_.count(in_.token("cell count"), "cell count");
    begin_data(n, Scalar::i32, "CELL_TYPES");
    types_.reserve(static_cast<std::size_t>(n));
    for (std::uint64_t i = 0; i < n; ++i) types_.push_back(integer(Scalar::i32, "cell type"));
  }

  [[noreturn]] void fail_at(std::size_t where, const std::string& message) const {
    if (binary_) in_.fail_at_offset(where, message);
    in_.fail_at_line(where, message);
  }

  std::uint32_t point_index(const CellList& list, std::size_t cell, std::int64_t v) const {
    if (v < 0 || static_cast<std::uint64_t>(v) >= mesh_.points.size())
      fail_at(list.where, "cell " + std::to_string(cell) + ": point index " + std::to_string(v) + " out of range (" +
                              std::to_string(mesh_.points.size()) + " points)");
    return static_cast<std::uint32_t>(v);
  }

  void add_grid_cells() {
    if (types_.size() != cells_.count())
      fail_at(types_where_, "CELL_TYPES has " + std::to_string(types_.size()) + " entries but CELLS has " +
                                std::to_string(cells_.count()) + " cells");
    for (std::size_t i = 0; i < types_.size(); ++i) {
      const std::int64_t type = types_[i];
      if (type != kVtkTriangle && type != kVtkTetra) continue;
      const auto b = static_cast<std::size_t>(cells_.offsets[i]);
      const auto k = static_cast<std::size_t>(cells_.offsets[i + 1]) - b;
      const std::size_t want = type == kVtkTriangle ? 3 : 4;
      if (k != want)
        fail_at(cells_.where, "cell " + std::to_string(i) + " of type " + std::to_string(type) + " has " +
                                  std::to_string(k) + " points instead of " + std::to_string(want));
      std::uint32_t v[4];
      for (std::size_t j = 0; j < k; ++j) v[j] = point_index(cells_, i, cells_.conn[b + j]);
      if (type == kVtkTriangle) mesh_.triangles.push_back({v[0], v[1], v[2]});
      else mesh_.tetrahedra.push_back({v[0], v[1], v[2], v[3]});
    }
  }

  void add_polydata(const CellList& list, bool strips) {
    std::vector<std::uint32_t> corners;
    for (std::size_t i = 0; i < list.count(); ++i) {
      const auto b = static_cast<std::size_t>(list.offsets[i]);
      const auto k = static_cast<std::size_t>(list.offsets[i + 1]) - b;
      if (k < 3)
        fail_at(list.where, std::string(strips ? "triangle strip " : "polygon ") + std::to_string(i) + " has " +
                                std::to_string(k) + " points (at least 3 needed)");
      corners.clear();
      for (std::size_t j = 0; j < k; ++j) corners.push_back(point_index(list, i, list.conn[b + j]));
      if (!strips) {
        add_fan(mesh_, corners.data(), k);
        continue;
      }
      for (std::size_t j = 0; j + 2 < k; ++j) {
        // Every other triangle of a strip is flipped to keep one orientation.
        if (j % 2 == 0) mesh_.triangles.push_back({corners[j], corners[j + 1], corners[j + 2]});
        else mesh_.triangles.push_back({corners[j + 1], corners[j], corners[j + 2]});
      }
    }
  }

  void skip_values(std::uint64_t n, Scalar t, std::string_view what) {
    begin_data(n, t, what);
    if (binary_) {
      in_.skip(n * scalar_size(t), what);
      return;
    }
    for (std::uint64_t i = 0; i < n; ++i) in_.token(what);
  }

  void skip_field() {
    in_.token("field name");
    const std::uint64_t arrays = in_.count(in_.token("number of arrays"), "number of arrays");
    for (std::uint64_t a = 0; a < arrays; ++a) {
      std::string_view name = in_.token("array name");
      if (iequals(name, "METADATA")) {
        skip_metadata();
        name = in_.token("array name");
      }
      const std::uint64_t comps = in_.count(in_.token("number of components"), "number of components");
      const std::uint64_t tuples = in_.count(in_.token("number of tuples"), "number of tuples");
      const Scalar t = data_type("field array");
      if (comps != 0 && tuples > std::numeric_limits<std::uint64_t>::max() / comps)
        in_.fail("field array size overflows");
      skip_values(comps * tuples, t, "field array");
    }
  }

  // A METADATA block runs to the first empty line.
  void skip_metadata() {
    in_.skip_line();
    std::string_view line;
    while (in_.next_line(line))
      if (trim(line).empty()) break;
  }

  Input in_;
  Mesh mesh_;
  CellList cells_;
  std::vector<std::int64_t> types_;
  std::size_t types_where_ = 0;
  bool binary_ = false;
  bool polydata_ = false;
  bool have_points_ = false;
  bool have_types_ = false;
};

std::uint8_t vtk_type(bool tet) { return tet ? 10 : 5; }

}  // namespace

Mesh read_vtk(const std::string& name, std::string_view data) { return Reader(name, data).run(); }

std::string write_vtk(const Mesh& m, const WriteOptions& opt) {
  const std::uint64_t ncells = m.triangles.size() + m.tetrahedra.size();
  const std::uint64_t size = 4 * std::uint64_t{m.triangles.size()} + 5 * std::uint64_t{m.tetrahedra.size()};
  constexpr auto kIntMax = static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max());
  if (m.points.size() > kIntMax || size > kIntMax)
    hmc::detail::fail(Status::invalid_argument, "mesh too large for the VTK legacy format's 32-bit cell lists");
  const bool bin = opt.binary;
  std::string out = "# vtk DataFile Version 3.0\nwritten by hmc\n";
  out += bin ? "BINARY\n" : "ASCII\n";
  out += "DATASET UNSTRUCTURED_GRID\nPOINTS ";
  append_uint(out, m.points.size());
  const bool f32 = bin && opt.float32;
  out += f32 ? " float\n" : " double\n";
  if (bin) out.reserve(out.size() + (f32 ? 12 : 24) * m.points.size() + 4 * size + 4 * ncells + 64);
  if (bin) {
    append_points(out, m.points, f32, true);
  } else {
    for (const Vec3& p : m.points) append_point_line(out, "", p, opt.precision);
  }
  if (bin) out += '\n';
  if (ncells == 0) return out;
  auto cell = [&](const std::uint32_t* v, std::uint32_t k) {
    if (bin) {
      append_bytes(out, k, true);
      for (std::uint32_t j = 0; j < k; ++j) append_bytes(out, v[j], true);
      return;
    }
    append_uint(out, k);
    for (std::uint32_t j = 0; j < k; ++j) {
      out += ' ';
      append_uint(out, v[j]);
    }
    out += '\n';
  };
  out += "CELLS ";
  append_uint(out, ncells);
  out += ' ';
  append_uint(out, size);
  out += '\n';
  for (const Triangle& t : m.triangles) cell(t.data(), 3);
  for (const Tetrahedron& t : m.tetrahedra) cell(t.data(), 4);
  if (bin) out += '\n';
  out += "CELL_TYPES ";
  append_uint(out, ncells);
  out += '\n';
  auto type = [&](std::uint32_t code) {
    if (bin) {
      append_bytes(out, code, true);
      return;
    }
    append_uint(out, code);
    out += '\n';
  };
  for (std::size_t i = 0; i < m.triangles.size(); ++i) type(vtk_type(false));
  for (std::size_t i = 0; i < m.tetrahedra.size(); ++i) type(vtk_type(true));
  if (bin) out += '\n';
  return out;
}

std::string write_vtu(const Mesh& m, const WriteOptions& opt) {
  const std::uint64_t ncells = m.triangles.size() + m.tetrahedra.size();
  std::string out =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <UnstructuredGrid>\n"
      "    <Piece NumberOfPoints=\"";
  append_uint(out, m.points.size());
  out += "\" NumberOfCells=\"";
  append_uint(out, ncells);
  out +=
      "\">\n"
      "      <Points>\n"
      "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const Vec3& p : m.points) append_point_line(out, "          ", p, opt.precision);
  out +=
      "        </DataArray>\n"
      "      </Points>\n"
      "      <Cells>\n"
      "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  auto cell = [&](const std::uint32_t* v, std::size_t k) {
    out += "          ";
    for (std::size_t j = 0; j < k; ++j) {
      if (j) out += ' ';
      append_uint(out, v[j]);
    }
    out += '\n';
  };
  for (const Triangle& t : m.triangles) cell(t.data(), 3);
  for (const Tetrahedron& t : m.tetrahedra) cell(t.data(), 4);
  out +=
      "        </DataArray>\n"
      "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  std::uint64_t offset = 0;
  auto line_of = [&](std::uint64_t v, std::uint64_t i) {
    out += (i % 16 == 0) ? "          " : " ";
    append_uint(out, v);
    if (i % 16 == 15 || i + 1 == ncells) out += '\n';
  };
  for (std::uint64_t i = 0; i < ncells; ++i) {
    offset += i < m.triangles.size() ? 3 : 4;
    line_of(offset, i);
  }
  out +=
      "        </DataArray>\n"
      "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::uint64_t i = 0; i < ncells; ++i) line_of(vtk_type(i >= m.triangles.size()), i);
  out +=
      "        </DataArray>\n"
      "      </Cells>\n"
      "    </Piece>\n"
      "  </UnstructuredGrid>\n"
      "</VTKFile>\n";
  return out;
}

}  // namespace hmc::io::detail
