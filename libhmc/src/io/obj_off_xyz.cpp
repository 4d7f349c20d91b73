// SPDX-License-Identifier: AGPL-3.0-or-later
// Wavefront OBJ, OFF and XYZ point lists: line-oriented text formats.
#include <limits>
#include <vector>

#include "io/common.hpp"
#include "io/input.hpp"

namespace hmc::io::detail {

namespace {

constexpr std::uint64_t kMaxPoints = std::numeric_limits<std::uint32_t>::max();

Vec3 read_xyz_fields(Input& in, Fields& f, std::string_view what) {
  Vec3 p;
  static const char* const axis[] = {"x coordinate", "y coordinate", "z coordinate"};
  for (int k = 0; k < 3; ++k) {
    std::string_view tok;
    if (!f.next(tok)) in.fail(std::string(what) + " has fewer than 3 coordinates");
    p[k] = in.real(tok, axis[k]);
  }
  return p;
}

void add_point(Input& in, Mesh& m, const Vec3& p) {
  if (m.points.size() >= kMaxPoints) in.fail("too many vertices for 32-bit indices");
  m.points.push_back(p);
}

}  // namespace

Mesh read_obj(const std::string& name, std::string_view data) {
  Input in(name, data, '#');
  Mesh m;
  MaxIndex max_index;  // positive indices may refer to vertices defined later
  std::vector<std::uint32_t> corners;
  Fields f;
  while (in.next_data_line(f)) {
    std::string_view kw;
    f.next(kw);
    if (kw == "v") {
      add_point(in, m, read_xyz_fields(in, f, "vertex"));
      continue;
    }
    if (kw != "f") continue;
    corners.clear();
    std::string_view tok;
    while (f.next(tok)) {
      const std::string_view vpart = tok.substr(0, tok.find('/'));
      std::int64_t v;
      if (!parse_int(vpart, v)) in.fail("bad face vertex " + quote(tok));
      if (v == 0) in.fail("face index 0 is invalid (OBJ indices start at 1)");
      std::int64_t idx;
      if (v < 0) {
        idx = static_cast<std::int64_t>(m.points.size()) + v;
        if (idx < 0)
          in.fail("relative face index " + std::to_string(v) + " out of range (" + std::to_string(m.points.size()) +
                  " vertices so far)");
      } else {
        idx = v - 1;
        if (static_cast<std::uint64_t>(idx) >= kMaxPoints)
          in.fail("face index " + std::to_string(v) + " out of range (" + std::to_string(m.points.size()) +
                  " vertices)");
        max_index.see(static_cast<std::uint64_t>(idx), in.line());
      }
      corners.push_back(static_cast<std::uint32_t>(idx));
    }
    if (corners.size() < 3)
      in.fail("face has " + std::to_string(corners.size()) + " vertices (at least 3 needed)");
    add_fan(m, corners.data(), corners.size());
  }
  if (max_index.any && max_index.value >= m.points.size())
    in.fail_at_line(max_index.line, "face index " + std::to_string(max_index.value + 1) + " out of range (" +
                                        std::to_string(m.points.size()) + " vertices)");
  return m;
}

Mesh read_off(const std::string& name, std::string_view data) {
  Input in(name, data, '#');
  Fields f;
  if (!in.next_data_line(f)) in.fail("empty file, expected an OFF header");
  std::string_view kw;
  f.next(kw);
  if (kw.size() < 3 || kw.substr(kw.size() - 3) != "OFF") in.fail("missing OFF header, found " + quote(kw));
  // Prefixes ST (texture), C (colour) and N (normal) only add columns after
  // x y z, which are ignored; 4 (homogeneous) and n (dimension) change them.
  for (char c : kw.substr(0, kw.size() - 3))
    if (c != 'S' && c != 'T' && c != 'C' && c != 'N') in.fail("unsupported OFF variant " + quote(kw));
  std::string_view tok;
  Fields counts = f;
  if (counts.done()) {
    if (!in.next_data_line(counts)) in.fail("missing vertex and face counts");
  } else {
    Fields peek = counts;
    peek.next(tok);
    if (tok == "BINARY") hmc::detail::fail(Status::unsupported_format, name + ": binary OFF is not supported");
  }
  if (!counts.next(tok)) in.fail("missing vertex count");
  const std::uint64_t nv = in.count(tok, "vertex count");
  if (!counts.next(tok)) in.fail("missing face count");
  const std::uint64_t nf = in.count(tok, "face count");
  if (nv > kMaxPoints) in.fail("too many vertices (" + std::to_string(nv) + ")");
  in.check_text_count(nv, 3, "vertex");
  Mesh m;
  m.points.reserve(static_cast<std::size_t>(nv));
  for (std::uint64_t i = 0; i < nv; ++i) {
    if (!in.next_data_line(f))
      in.fail("unexpected end of file after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
    m.points.push_back(read_xyz_fields(in, f, "vertex"));
  }
  in.check_text_count(nf, 4, "face");
  m.triangles.reserve(static_cast<std::size_t>(nf));
  std::vector<std::uint32_t> corners;
  for (std::uint64_t i = 0; i < nf; ++i) {
    if (!in.next_data_line(f))
      in.fail("unexpected end of file after " + std::to_string(i) + " of " + std::to_string(nf) + " faces");
    f.next(tok);
    const std::uint64_t n = in.count(tok, "face vertex count");
    if (n < 3) in.fail("face has " + std::to_string(n) + " vertices (at least 3 needed)");
    corners.clear();
    for (std::uint64_t k = 0; k < n; ++k) {
      if (!f.next(tok)) in.fail("face has fewer than the " + std::to_string(n) + " indices it declares");
      const std::int64_t v = in.integer(tok, "face vertex index");
      if (v < 0 || static_cast<std::uint64_t>(v) >= nv)
        in.fail("face index " + std::to_string(v) + " out of range (" + std::to_string(nv) + " vertices)");
      corners.push_back(static_cast<std::uint32_t>(v));
    }
    add_fan(m, corners.data(), corners.size());
  }
  return m;
}

Mesh read_xyz(const std::string& name, std::string_view data) {
  Input in(name, data, '#');
  Mesh m;
  Fields f;
  while (in.next_data_line(f, true)) add_point(in, m, read_xyz_fields(in, f, "point"));
  return m;
}

std::string write_obj(const Mesh& m, const WriteOptions& opt) {
  std::string out = "# written by hmc\n";
  for (const Vec3& p : m.points) append_point_line(out, "v ", p, opt.precision);
  for (const Triangle& t : m.triangles) {
    out += "f ";
    append_uint(out, std::uint64_t{t[0]} + 1);
    out += ' ';
    append_uint(out, std::uint64_t{t[1]} + 1);
    out += ' ';
    append_uint(out, std::uint64_t{t[2]} + 1);
    out += '\n';
  }
  return out;
}

std::string write_xyz(const Mesh& m, const WriteOptions& opt) {
  std::string out;
  for (const Vec3& p : m.points) append_point_line(out, "", p, opt.precision);
  return out;
}

}  // namespace hmc::io::detail
