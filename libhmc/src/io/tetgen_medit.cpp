// SPDX-License-Identifier: AGPL-3.0-or-later
// TetGen .node/.ele/.face and MEDIT .mesh (ascii): the volume mesh formats
// of TetGen and the INRIA tools.
#include <array>
#include <filesystem>
#include <limits>
#include <vector>

#include "io/common.hpp"
#include "io/input.hpp"

namespace hmc::io::detail {

namespace {

namespace fs = std::filesystem;
constexpr std::uint64_t kMaxPoints = std::numeric_limits<std::uint32_t>::max();

std::string_view field(Input& in, Fields& f, std::string_view what) {
  std::string_view tok;
  if (!f.next(tok)) in.fail("missing " + std::string(what));
  return tok;
}

// Reads `n` indices from the row into `out`, rebased by `base` and checked
// against `nv` points.
template <std::size_t N>
void read_corners(Input& in, Fields& f, std::int64_t base, std::uint64_t nv, std::array<std::uint32_t, N>& out) {
  for (std::size_t k = 0; k < N; ++k) {
    const std::string_view tok = field(in, f, "node index");
    const std::int64_t v = in.integer(tok, "node index");
    // v - base cannot overflow: base is 0 or 1 and v > INT64_MIN when rebased below.
    if (v < base || static_cast<std::uint64_t>(v - base) >= nv)
      in.fail("node index " + std::to_string(v) + " out of range (" + std::to_string(nv) + " nodes numbered from " +
              std::to_string(base) + ")");
    out[k] = static_cast<std::uint32_t>(v - base);
  }
}

std::int64_t read_node_file(const std::string& path, Mesh& m) {
  const std::string data = load_file(path);
  Input in(path, data, '#');
  Fields f;
  if (!in.next_data_line(f)) in.fail("empty .node file, expected a header");
  const std::uint64_t n = in.count(field(in, f, "point count"), "point count");
  std::string_view tok;
  const std::uint64_t dim = f.next(tok) ? in.count(tok, "dimension") : 3;
  if (dim != 3) in.fail("dimension " + std::to_string(dim) + " is not supported (only 3)");
  if (n > kMaxPoints) in.fail("too many points (" + std::to_string(n) + ")");
  in.check_text_count(n, 4, "point");
  m.points.reserve(static_cast<std::size_t>(n));
  std::int64_t base = 0;
  for (std::uint64_t i = 0; i < n; ++i) {
    if (!in.next_data_line(f))
      in.fail("unexpected end of file after " + std::to_string(i) + " of " + std::to_string(n) + " points");
    const std::int64_t index = in.integer(field(in, f, "point index"), "point index");
    if (i == 0) {
      if (index != 0 && index != 1) in.fail("first point index must be 0 or 1, not " + std::to_string(index));
      base = index;
    } else if (index != base + static_cast<std::int64_t>(i)) {
      in.fail("point index " + std::to_string(index) + " out of sequence (expected " +
              std::to_string(base + static_cast<std::int64_t>(i)) + ")");
    }
    Vec3 p;
    p[0] = in.real(field(in, f, "x coordinate"), "x coordinate");
    p[1] = in.real(field(in, f, "y coordinate"), "y coordinate");
    p[2] = in.real(field(in, f, "z coordinate"), "z coordinate");
    m.points.push_back(p);
  }
  return base;
}

void read_ele_file(const std::string& path, std::int64_t base, Mesh& m) {
  const std::string data = load_file(path);
  Input in(path, data, '#');
  Fields f;
  if (!in.next_data_line(f)) in.fail("empty .ele file, expected a header");
  const std::uint64_t n = in.count(field(in, f, "tetrahedron count"), "tetrahedron count");
  std::string_view tok;
  const std::uint64_t per = f.next(tok) ? in.count(tok, "nodes per tetrahedron") : 4;
  if (per != 4 && per != 10) in.fail("nodes per tetrahedron must be 4 or 10, not " + std::to_string(per));
  in.check_text_count(n, 1 + per, "tetrahedron");
  m.tetrahedra.reserve(static_cast<std::size_t>(n));
  for (std::uint64_t i = 0; i < n; ++i) {
    if (!in.next_data_line(f))
      in.fail("unexpected end of file after " + std::to_string(i) + " of " + std::to_string(n) + " tetrahedra");
    in.integer(field(in, f, "tetrahedron index"), "tetrahedron index");
    Tetrahedron t;
    read_corners(in, f, base, m.points.size(), t);
    m.tetrahedra.push_back(t);
  }
}

void read_face_file(const std::string& path, std::int64_t base, Mesh& m) {
  const std::string data = load_file(path);
  Input in(path, data, '#');
  Fields f;
  if (!in.next_data_line(f)) in.fail("empty .face file, expected a header");
  const std::uint64_t n = in.count(field(in, f, "face count"), "face count");
  in.check_text_count(n, 4, "face");
  m.triangles.reserve(static_cast<std::size_t>(n));
  for (std::uint64_t i = 0; i < n; ++i) {
    if (!in.next_data_line(f))
      in.fail("unexpected end of file after " + std::to_string(i) + " of " + std::to_string(n) + " faces");
    in.integer(field(in, f, "face index"), "face index");
    Triangle t;
    read_corners(in, f, base, m.points.size(), t);
    m.triangles.push_back(t);
  }
}

bool is_file(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

// ----------------------------------------------------------------- MEDIT --

// Sections that are skipped, with the number of fields of one entry.
struct Skipped {
  const char* keyword;
  std::uint64_t fields;
};
const Skipped kSkipped[] = {
    {"Edges", 3},           {"Corners", 1},           {"Ridges", 1},          {"RequiredVertices", 1},
    {"RequiredEdges", 1},   {"RequiredTriangles", 1}, {"RequiredQuadrilaterals", 1},
    {"RequiredTetrahedra", 1}, {"Quadrilaterals", 5}, {"Hexahedra", 9},        {"Prisms", 7},
    {"Pyramids", 6},        {"Normals", 3},           {"Tangents", 3},        {"NormalAtVertices", 2},
    {"NormalAtTriangleVertices", 3}, {"TangentAtEdges", 3}, {"EdgesP2", 4},   {"TrianglesP2", 7},
    {"TetrahedraP2", 11},
};

template <std::size_t N>
void read_medit_elements(Input& in, std::vector<std::array<std::uint32_t, N>>& out, MaxIndex& max_index,
                         const char* what) {
  const std::uint64_t n = in.count(in.token("entry count"), "entry count");
  in.check_text_count(n, N + 1, what);
  out.reserve(out.size() + static_cast<std::size_t>(n));
  for (std::uint64_t i = 0; i < n; ++i) {
    std::array<std::uint32_t, N> e;
    for (std::size_t k = 0; k < N; ++k) {
      const std::int64_t v = in.integer(in.token("vertex index"), "vertex index");
      if (v < 1 || static_cast<std::uint64_t>(v) > kMaxPoints)
        in.fail("vertex index " + std::to_string(v) + " out of range (MEDIT indices start at 1)");
      max_index.see(static_cast<std::uint64_t>(v), in.line());
      e[k] = static_cast<std::uint32_t>(v - 1);
    }
    in.integer(in.token("reference"), "reference");
    out.push_back(e);
  }
}

void write_medit_cells(std::string& out, const char* keyword, const std::uint32_t* idx, std::size_t n,
                       std::size_t per) {
  if (n == 0) return;
  out += keyword;
  out += '\n';
  append_uint(out, n);
  out += '\n';
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < per; ++k) {
      append_uint(out, std::uint64_t{idx[i * per + k]} + 1);
      out += ' ';
    }
    out += "0\n";
  }
}

}  // namespace

TetgenPaths tetgen_paths(const std::string& path) {
  const fs::path p(path);
  const std::string ext = to_lower(p.extension().string());
  std::string stem = path;
  if (ext == ".node" || ext == ".ele" || ext == ".face") stem = path.substr(0, path.size() - ext.size());
  return {stem + ".node", stem + ".ele", stem + ".face"};
}

Mesh read_tetgen(const std::string& path) {
  const TetgenPaths paths = tetgen_paths(path);
  Mesh m;
  const std::int64_t base = read_node_file(paths.node, m);
  if (is_file(paths.ele) || to_lower(fs::path(path).extension().string()) == ".ele")
    read_ele_file(paths.ele, base, m);
  if (is_file(paths.face)) read_face_file(paths.face, base, m);
  return m;
}

Mesh read_medit(const std::string& name, std::string_view data) {
  // The binary format starts with the int32 1 (in either byte order).
  if (data.size() >= 4 && (data.compare(0, 4, std::string_view("\1\0\0\0", 4)) == 0 ||
                           data.compare(0, 4, std::string_view("\0\0\0\1", 4)) == 0))
    hmc::detail::fail(Status::unsupported_format, name + ": binary MEDIT (.meshb) files are not supported");
  Input in(name, data, '#');
  std::string_view tok = in.token("MeshVersionFormatted");
  if (!iequals(tok, "MeshVersionFormatted")) in.fail("expected MeshVersionFormatted, found " + quote(tok));
  in.integer(in.token("format version"), "format version");
  Mesh m;
  MaxIndex max_index;
  bool have_vertices = false;
  while (in.next_token(tok)) {
    if (iequals(tok, "End")) break;
    if (iequals(tok, "Dimension")) {
      const std::int64_t d = in.integer(in.token("dimension"), "dimension");
      if (d != 3) in.fail("Dimension " + std::to_string(d) + " is not supported (only 3)");
    } else if (iequals(tok, "Vertices")) {
      if (have_vertices) in.fail("second Vertices section");
      have_vertices = true;
      const std::uint64_t n = in.count(in.token("vertex count"), "vertex count");
      if (n > kMaxPoints) in.fail("too many vertices (" + std::to_string(n) + ")");
      in.check_text_count(n, 4, "vertex");
      m.points.reserve(static_cast<std::size_t>(n));
      for (std::uint64_t i = 0; i < n; ++i) {
        Vec3 p;
        p[0] = in.real(in.token("x coordinate"), "x coordinate");
        p[1] = in.real(in.token("y coordinate"), "y coordinate");
        p[2] = in.real(in.token("z coordinate"), "z coordinate");
        in.integer(in.token("reference"), "reference");
        m.points.push_back(p);
      }
    } else if (iequals(tok, "Triangles")) {
      read_medit_elements(in, m.triangles, max_index, "triangle");
    } else if (iequals(tok, "Tetrahedra")) {
      read_medit_elements(in, m.tetrahedra, max_index, "tetrahedron");
    } else {
      const Skipped* s = nullptr;
      for (const Skipped& k : kSkipped)
        if (iequals(tok, k.keyword)) s = &k;
      if (!s) in.fail("unknown MEDIT keyword " + quote(tok));
      const std::uint64_t n = in.count(in.token("entry count"), std::string(s->keyword) + " count");
      in.check_text_count(n, s->fields, s->keyword);
      const std::string what = std::string("entry of ") + s->keyword;
      for (std::uint64_t i = 0; i < n * s->fields; ++i) in.token(what);
    }
  }
  if (max_index.any && max_index.value > m.points.size())
    in.fail_at_line(max_index.line, "vertex index " + std::to_string(max_index.value) + " out of range (" +
                                        std::to_string(m.points.size()) + " vertices)");
  return m;
}

std::string write_medit(const Mesh& m, const WriteOptions& opt) {
  std::string out = "MeshVersionFormatted 2\nDimension 3\n";
  if (!m.points.empty()) {
    out += "Vertices\n";
    append_uint(out, m.points.size());
    out += '\n';
    for (const Vec3& p : m.points) {
      for (double c : p) {
        append_real(out, c, opt.precision);
        out += ' ';
      }
      out += "0\n";
    }
  }
  write_medit_cells(out, "Triangles", m.triangles.empty() ? nullptr : m.triangles[0].data(), m.triangles.size(), 3);
  write_medit_cells(out, "Tetrahedra", m.tetrahedra.empty() ? nullptr : m.tetrahedra[0].data(), m.tetrahedra.size(),
                    4);
  out += "End\n";
  return out;
}

TetgenFiles write_tetgen(const Mesh& m, const WriteOptions& opt) {
  TetgenFiles f;
  append_uint(f.node, m.points.size());
  f.node += " 3 0 0\n";
  for (std::size_t i = 0; i < m.points.size(); ++i) {
    append_uint(f.node, i);
    for (double c : m.points[i]) {
      f.node += ' ';
      append_real(f.node, c, opt.precision);
    }
    f.node += '\n';
  }
  if (!m.tetrahedra.empty()) {
    append_uint(f.ele, m.tetrahedra.size());
    f.ele += " 4 0\n";
    for (std::size_t i = 0; i < m.tetrahedra.size(); ++i) {
      append_uint(f.ele, i);
      for (std::uint32_t v : m.tetrahedra[i]) {
        f.ele += ' ';
        append_uint(f.ele, v);
      }
      f.ele += '\n';
    }
  }
  if (!m.triangles.empty()) {
    append_uint(f.face, m.triangles.size());
    f.face += " 0\n";
    for (std::size_t i = 0; i < m.triangles.size(); ++i) {
      append_uint(f.face, i);
      for (std::uint32_t v : m.triangles[i]) {
        f.face += ' ';
        append_uint(f.face, v);
      }
      f.face += '\n';
    }
  }
  return f;
}

}  // namespace hmc::io::detail
