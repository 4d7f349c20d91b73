// SPDX-License-Identifier: AGPL-3.0-or-later
// PLY (Stanford polygon format): ascii, binary little- and big-endian.
#include <cmath>
#include <limits>
#include <vector>

#include "io/common.hpp"
#include "io/input.hpp"

namespace hmc::io::detail {

namespace {

enum class Encoding { none, ascii, binary_le, binary_be };

// What the reader does with a property's values.
enum class Role : std::uint8_t { skip, x, y, z, corners };

struct Property {
  std::string name;
  bool is_list = false;
  Scalar count_type = Scalar::u8;
  Scalar type = Scalar::f32;
  Role role = Role::skip;
  std::string label;  // "property NAME of element ELEMENT", for messages
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::size_t line = 0;
  std::vector<Property> props;
  bool is_vertex = false;
  bool is_face = false;
};

bool scalar_from_name(std::string_view s, Scalar& t) noexcept {
  struct Entry {
    const char* name;
    Scalar type;
  };
  static const Entry table[] = {
      {"char", Scalar::i8},     {"int8", Scalar::i8},       {"uchar", Scalar::u8},    {"uint8", Scalar::u8},
      {"short", Scalar::i16},   {"int16", Scalar::i16},     {"ushort", Scalar::u16},  {"uint16", Scalar::u16},
      {"int", Scalar::i32},     {"int32", Scalar::i32},     {"uint", Scalar::u32},    {"uint32", Scalar::u32},
      {"float", Scalar::f32},   {"float32", Scalar::f32},   {"double", Scalar::f64},  {"float64", Scalar::f64},
      {"int64", Scalar::i64},   {"uint64", Scalar::u64},
  };
  for (const Entry& e : table)
    if (s == e.name) {
      t = e.type;
      return true;
    }
  return false;
}

struct Header {
  Encoding encoding = Encoding::none;
  std::vector<Element> elements;
  const Element* vertex = nullptr;
  std::uint32_t vertex_count = 0;
};

Header read_header(Input& in) {
  std::string_view line;
  if (!in.next_line(line) || trim(line) != "ply") in.fail("not a PLY file (the first line is not 'ply')");
  Header h;
  bool ended = false;
  Fields f;
  while (!ended && in.next_line(line)) {
    f = Fields(line);
    std::string_view kw;
    if (!f.next(kw)) continue;
    if (kw == "comment" || kw == "obj_info") continue;
    if (kw == "format") {
      std::string_view enc, ver;
      if (!f.next(enc) || !f.next(ver)) in.fail("format line needs an encoding and a version");
      if (enc == "ascii") h.encoding = Encoding::ascii;
      else if (enc == "binary_little_endian") h.encoding = Encoding::binary_le;
      else if (enc == "binary_big_endian") h.encoding = Encoding::binary_be;
      else in.fail("unknown PLY format " + quote(enc));
      if (ver.empty() || ver[0] != '1') in.fail("unsupported PLY version " + quote(ver));
    } else if (kw == "element") {
      std::string_view name, count;
      if (!f.next(name) || !f.next(count)) in.fail("element line needs a name and a count");
      Element e;
      e.name = std::string(name);
      e.count = in.count(count, "element count");
      e.line = in.line();
      h.elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (h.elements.empty()) in.fail("property before any element");
      Property p;
      std::string_view t, name;
      if (!f.next(t)) in.fail("property line needs a type");
      if (t == "list") {
        std::string_view ct, it;
        if (!f.next(ct) || !f.next(it) || !f.next(name)) in.fail("list property needs a count type, a type and a name");
        if (!scalar_from_name(ct, p.count_type)) in.fail("unknown property type " + quote(ct));
        if (!scalar_from_name(it, p.type)) in.fail("unknown property type " + quote(it));
        if (!scalar_is_integer(p.count_type)) in.fail("list count type " + quote(ct) + " is not an integer type");
        p.is_list = true;
      } else {
        if (!f.next(name)) in.fail("property line needs a name");
        if (!scalar_from_name(t, p.type)) in.fail("unknown property type " + quote(t));
      }
      p.name = std::string(name);
      h.elements.back().props.push_back(std::move(p));
    } else if (kw == "end_header") {
      ended = true;
    } else {
      in.fail("unknown PLY header keyword " + quote(kw));
    }
  }
  if (!ended) in.fail("missing end_header");
  if (h.encoding == Encoding::none) in.fail("missing format line in the PLY header");

  Element* face = nullptr;
  Element* vertex = nullptr;
  for (Element& e : h.elements) {
    if (e.name == "vertex" && !vertex) vertex = &e;
    if (e.name == "face" && !face) face = &e;
  }
  for (Element& e : h.elements)
    for (Property& p : e.props) p.label = "property " + p.name + " of element " + e.name;
  if (!vertex) in.fail("PLY header has no vertex element");
  vertex->is_vertex = true;
  for (const char* axis : {"x", "y", "z"}) {
    bool found = false;
    for (Property& p : vertex->props) {
      if (p.name != axis) continue;
      if (p.is_list) in.fail_at_line(vertex->line, std::string("vertex property ") + axis + " is a list");
      p.role = axis[0] == 'x' ? Role::x : axis[0] == 'y' ? Role::y : Role::z;
      found = true;
      break;
    }
    if (!found) in.fail_at_line(vertex->line, std::string("vertex element has no property ") + axis);
  }
  if (vertex->count > std::numeric_limits<std::uint32_t>::max())
    in.fail_at_line(vertex->line, "too many vertices (" + std::to_string(vertex->count) + ")");
  h.vertex_count = static_cast<std::uint32_t>(vertex->count);
  h.vertex = vertex;
  if (face) {
    face->is_face = true;
    bool found = false;
    for (Property& p : face->props) {
      if (p.name != "vertex_indices" && p.name != "vertex_index") continue;
      if (!p.is_list) in.fail_at_line(face->line, "face property " + p.name + " is not a list");
      if (!scalar_is_integer(p.type)) in.fail_at_line(face->line, "face property " + p.name + " has a non-integer type");
      p.role = Role::corners;
      found = true;
      break;
    }
    if (!found) in.fail_at_line(face->line, "face element has no vertex_indices list property");
  }
  return h;
}

// ----------------------------------------------------------------- ascii --

Mesh read_ascii(Input& in, const Header& h) {
  Mesh mesh;
  std::vector<std::uint32_t> corners;
  for (const Element& e : h.elements) {
    in.check_text_count(e.count, e.props.empty() ? 1 : e.props.size(), "element " + e.name);
    if (e.is_vertex) mesh.points.reserve(static_cast<std::size_t>(e.count));
    if (e.is_face) mesh.triangles.reserve(static_cast<std::size_t>(e.count));
    for (std::uint64_t row = 0; row < e.count; ++row) {
      Fields f;
      if (!in.next_data_line(f))
        in.fail("unexpected end of file: element " + e.name + " has " + std::to_string(row) + " of " +
                std::to_string(e.count) + " rows");
      Vec3 p{0, 0, 0};
      for (const Property& prop : e.props) {
        std::string_view tok;
        if (!f.next(tok)) in.fail("missing value for " + prop.label);
        if (!prop.is_list) {
          if (prop.role == Role::x) p[0] = in.real(tok, "x coordinate");
          else if (prop.role == Role::y) p[1] = in.real(tok, "y coordinate");
          else if (prop.role == Role::z) p[2] = in.real(tok, "z coordinate");
          continue;
        }
        const std::uint64_t n = in.count(tok, prop.label);
        if (prop.role != Role::corners) {
          for (std::uint64_t i = 0; i < n; ++i)
            if (!f.next(tok)) in.fail("list " + prop.name + " has fewer than " + std::to_string(n) + " values");
          continue;
        }
        if (n < 3) in.fail("face " + std::to_string(row) + " has " + std::to_string(n) + " vertices (at least 3 needed)");
        corners.clear();
        for (std::uint64_t i = 0; i < n; ++i) {
          if (!f.next(tok)) in.fail("face " + std::to_string(row) + " has fewer than " + std::to_string(n) + " indices");
          const std::int64_t v = in.integer(tok, "face vertex index");
          if (v < 0 || static_cast<std::uint64_t>(v) >= h.vertex_count)
            in.fail("face vertex index " + std::to_string(v) + " out of range (" + std::to_string(h.vertex_count) +
                    " vertices)");
          corners.push_back(static_cast<std::uint32_t>(v));
        }
        add_fan(mesh, corners.data(), corners.size());
      }
      if (!f.done()) in.fail("more values than the properties of element " + e.name + " declare");
      if (e.is_vertex) mesh.points.push_back(p);
    }
  }
  return mesh;
}

// ---------------------------------------------------------------- binary --

// Minimal bytes of one row (lists counted as empty), to bound declared counts.
std::uint64_t min_row_bytes(const Element& e) {
  std::uint64_t n = 0;
  for (const Property& p : e.props) n += scalar_size(p.is_list ? p.count_type : p.type);
  return n;
}

Mesh read_binary(Input& in, const Header& h, bool big) {
  in.set_binary(true);
  {
    std::uint64_t budget = in.remaining();
    for (const Element& e : h.elements) {
      const std::uint64_t row = min_row_bytes(e);
      if (row > 0 && e.count > budget / row)
        in.fail_at_line(e.line, "element " + e.name + " count " + std::to_string(e.count) + " needs more than the " +
                                    std::to_string(in.remaining()) + " bytes of binary data in the file");
      budget -= e.count * row;
    }
  }
  Mesh mesh;
  std::vector<std::uint32_t> corners;
  for (const Element& e : h.elements) {
    if (e.is_vertex) mesh.points.reserve(static_cast<std::size_t>(e.count));
    if (e.is_face) mesh.triangles.reserve(static_cast<std::size_t>(e.count));
    bool fixed = true;
    for (const Property& p : e.props) fixed = fixed && !p.is_list;
    if (!e.is_vertex && !e.is_face && fixed) {
      in.skip(e.count * min_row_bytes(e), "element " + e.name);
      continue;
    }
    for (std::uint64_t row = 0; row < e.count; ++row) {
      Vec3 p{0, 0, 0};
      for (const Property& prop : e.props) {
        if (!prop.is_list) {
          if (prop.role == Role::skip) {
            in.skip(scalar_size(prop.type), prop.label);
            continue;
          }
          const double v = in.read_scalar(prop.type, big, prop.label);
          if (!std::isfinite(v)) in.fail("non-finite " + prop.name + " coordinate of vertex " + std::to_string(row));
          p[prop.role == Role::x ? 0 : prop.role == Role::y ? 1 : 2] = v;
          continue;
        }
        const std::int64_t n = in.read_integer(prop.count_type, big, prop.label);
        if (n < 0) in.fail("negative list length " + std::to_string(n) + " of " + prop.name);
        const std::size_t item = scalar_size(prop.type);
        if (static_cast<std::uint64_t>(n) > in.remaining() / item)
          in.fail("list " + prop.name + " of length " + std::to_string(n) + " runs past the end of the file");
        if (prop.role != Role::corners) {
          in.skip(static_cast<std::uint64_t>(n) * item, prop.label);
          continue;
        }
        if (n < 3) in.fail("face " + std::to_string(row) + " has " + std::to_string(n) + " vertices (at least 3 needed)");
        corners.clear();
        for (std::int64_t i = 0; i < n; ++i) {
          const std::int64_t v = in.read_integer(prop.type, big, "face vertex index");
          if (v < 0 || static_cast<std::uint64_t>(v) >= h.vertex_count)
            in.fail("face vertex index " + std::to_string(v) + " out of range (" + std::to_string(h.vertex_count) +
                    " vertices)");
          corners.push_back(static_cast<std::uint32_t>(v));
        }
        add_fan(mesh, corners.data(), corners.size());
      }
      if (e.is_vertex) mesh.points.push_back(p);
    }
  }
  return mesh;
}

void add_header(std::string& out, const Mesh& m, bool binary, bool float32) {
  out += "ply\nformat ";
  out += binary ? "binary_little_endian" : "ascii";
  out += " 1.0\ncomment written by hmc\nelement vertex ";
  append_uint(out, m.points.size());
  out += binary && float32 ? "\nproperty float x\nproperty float y\nproperty float z\n"
                            : "\nproperty double x\nproperty double y\nproperty double z\n";
  if (!m.triangles.empty()) {
    out += "element face ";
    append_uint(out, m.triangles.size());
    out += "\nproperty list uchar int vertex_indices\n";
  }
  out += "end_header\n";
}

}  // namespace

Mesh read_ply(const std::string& name, std::string_view data) {
  Input in(name, data);
  const Header h = read_header(in);
  if (h.encoding == Encoding::ascii) return read_ascii(in, h);
  return read_binary(in, h, h.encoding == Encoding::binary_be);
}

std::string write_ply(const Mesh& m, const WriteOptions& opt) {
  if (m.points.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    hmc::detail::fail(Status::invalid_argument, "too many points for PLY int indices");
  std::string out;
  add_header(out, m, opt.binary, opt.float32);
  if (opt.binary) {
    out.reserve(out.size() + m.points.size() * (opt.float32 ? 12 : 24) + m.triangles.size() * 13);
    append_points(out, m.points, opt.float32, false);
    for (const Triangle& t : m.triangles) {
      out += '\3';
      for (std::uint32_t v : t) append_bytes(out, v, false);
    }
    return out;
  }
  for (const Vec3& p : m.points) append_point_line(out, "", p, opt.precision);
  for (const Triangle& t : m.triangles) {
    out += "3 ";
    append_uint(out, t[0]);
    out += ' ';
    append_uint(out, t[1]);
    out += ' ';
    append_uint(out, t[2]);
    out += '\n';
  }
  return out;
}

}  // namespace hmc::io::detail
