// SPDX-License-Identifier: AGPL-3.0-or-later
// Boundary / inner classification (thesis §3.2 solid angles, §3.3 faces).
#include <algorithm>
#include <cmath>

#include "delaunay/delaunay.hpp"
#include "delaunay/predicates.hpp"
#include "encoder/hierarchy/hierarchy.hpp"
#include "encoder/hierarchy/internal.hpp"
#include "util/error.hpp"
#include "util/single_faces.hpp"

namespace hmc::detail {

namespace hierarchy {

std::vector<std::array<std::uint32_t, 3>> boundary_faces(const LevelMesh& m, Kind kind,
                                                         std::vector<std::uint8_t>* on_boundary_face) {
  const std::size_t n = point_count(m);
  std::vector<std::array<std::uint32_t, 3>> out;
  if (on_boundary_face) on_boundary_face->assign(n, 0);
  if (kind == Kind::surface) {
    for (const auto& t : m.triangles)
      if (usable(t, n)) out.push_back(t);
  } else if (kind == Kind::volume) {
    // The usable tetrahedra, each with its orientation in the top bit; their
    // faces are made as single_faces() asks for them, numbered in 32 bits.
    if (m.tetrahedra.size() >= (std::size_t{1} << 30))
      fail(Status::invalid_argument, "boundary classification: too many tetrahedra");
    std::vector<std::uint32_t> tets;
    tets.reserve(m.tetrahedra.size());
    for (std::size_t i = 0; i < m.tetrahedra.size(); ++i) {
      const auto& t = m.tetrahedra[i];
      if (!usable(t, n)) continue;
      const auto& p = *m.points;  // set: a usable tetrahedron's vertices are below its size
      const bool negative = orient3d(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) < 0;
      tets.push_back(static_cast<std::uint32_t>(i) | (negative ? 0x80000000u : 0u));
    }
    out = single_faces(4 * tets.size(), [&](std::size_t i) {
      const std::uint32_t e = tets[i / 4];
      const auto& t = m.tetrahedra[e & 0x7FFFFFFFu];
      const int k = static_cast<int>(i % 4);
      std::array<std::uint32_t, 3> f;
      for (int j = 0; j < 3; ++j) f[static_cast<std::size_t>(j)] = t[static_cast<std::size_t>(kFaceVertices[k][j])];
      if (e & 0x80000000u) std::swap(f[1], f[2]);
      return f;
    });
  }
  if (on_boundary_face)
    for (const auto& f : out)
      for (std::uint32_t v : f) (*on_boundary_face)[v] = 1;
  return out;
}

}  // namespace hierarchy

namespace {

constexpr double kPi = 3.14159265358979323846;

double norm(const IVec3& a) {
  const auto x = static_cast<double>(a.x), y = static_cast<double>(a.y), z = static_cast<double>(a.z);
  return std::sqrt(x * x + y * y + z * z);
}
double dot(const IVec3& a, const IVec3& b) {
  return static_cast<double>(a.x * b.x + a.y * b.y + a.z * b.z);  // |terms| < 2^42: exact in int64
}

}  // namespace

Classification classify(const LevelMesh& m, Kind kind) {
  const std::size_t n = hierarchy::point_count(m);
  Classification c;
  if (kind != Kind::volume) {
    c.boundary.assign(n, 1);
    c.boundary_by_angle.assign(n, 1);
    c.boundary_count = n;
    return c;
  }
  std::vector<std::uint8_t> in_tet(n, 0);
  c.solid_angle.assign(n, 0.0);
  for (const auto& t : m.tetrahedra) {
    if (!hierarchy::usable(t, n)) continue;
    const auto& p = *m.points;
    const double six_v = std::fabs(static_cast<double>(orient3d_value(p[t[0]], p[t[1]], p[t[2]], p[t[3]])));
    for (int i = 0; i < 4; ++i) {
      in_tet[t[i]] = 1;
      const GridPoint& o = p[t[i]];
      const IVec3 a = sub(p[t[(i + 1) & 3]], o), b = sub(p[t[(i + 2) & 3]], o), d = sub(p[t[(i + 3) & 3]], o);
      const double la = norm(a), lb = norm(b), ld = norm(d);
      const double den = la * lb * ld + dot(a, b) * ld + dot(a, d) * lb + dot(b, d) * la;
      c.solid_angle[t[i]] += 2.0 * std::atan2(six_v, den);
    }
  }
  c.faces = hierarchy::boundary_faces(m, kind, &c.boundary);
  c.boundary_by_angle.assign(n, 0);
  for (std::size_t v = 0; v < n; ++v) {
    if (!in_tet[v]) c.boundary[v] = 1;
    c.boundary_by_angle[v] = !in_tet[v] || c.solid_angle[v] < 4.0 * kPi - kSolidAngleTolerance;
    c.boundary_count += c.boundary[v];
    c.disagreements += c.boundary[v] != c.boundary_by_angle[v];
  }
  return c;
}

}  // namespace hmc::detail
