// SPDX-License-Identifier: AGPL-3.0-or-later
// Boundary vertex types and Dmax errors (thesis §3.4.1; see hierarchy.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "delaunay/predicates.hpp"
#include "encoder/hierarchy/hierarchy.hpp"
#include "encoder/hierarchy/internal.hpp"

namespace hmc::detail {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Vec128 {
  Int128 x = 0, y = 0, z = 0;
};

IVec3 cross(const IVec3& a, const IVec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double length(double x, double y, double z) { return std::sqrt(x * x + y * y + z * z); }
double length(const IVec3& a) {
  return length(static_cast<double>(a.x), static_cast<double>(a.y), static_cast<double>(a.z));
}
double length(const Vec128& a) {
  return length(static_cast<double>(a.x), static_cast<double>(a.y), static_cast<double>(a.z));
}
std::int64_t idot(const IVec3& a, const IVec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Distance from v to the segment [a, b]; exact 0 when v lies on it.
double segment_distance(const GridPoint& v, const GridPoint& a, const GridPoint& b) {
  const IVec3 ab = sub(b, a), av = sub(v, a);
  const std::int64_t len2 = idot(ab, ab), t = idot(av, ab);
  if (len2 == 0 || t <= 0) return length(av);
  if (t >= len2) return length(sub(v, b));
  return length(cross(ab, av)) / std::sqrt(static_cast<double>(len2));
}

// Small union-find over the faces around one vertex.
std::uint32_t find(std::vector<std::uint32_t>& parent, std::uint32_t x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

}  // namespace

BoundaryAnalysis analyze_boundary(const LevelMesh& m, Kind kind, const Classification& c, const VertexGraph& g,
                                  double feature_angle_deg) {
  const std::size_t n = hierarchy::point_count(m);
  BoundaryAnalysis r;
  r.type.assign(n, BoundaryVertexType::none);
  r.error.assign(n, kInf);
  r.local_length.assign(n, 0.0);
  if (n == 0) return r;
  const auto& p = *m.points;

  for (std::uint32_t v = 0; v < n; ++v)
    for (const std::uint32_t* u = g.begin(v); u != g.end(v); ++u)
      r.local_length[v] = std::max(r.local_length[v], length(sub(p[*u], p[v])));

  // classify() found the faces of a volume already (sorting every face of
  // every tetrahedron); a surface's are its triangles.
  std::vector<std::array<std::uint32_t, 3>> own;
  if (kind != Kind::volume) own = hierarchy::boundary_faces(m, kind);
  const auto& faces = kind == Kind::volume ? c.faces : own;
  r.boundary_faces = faces.size();
  std::vector<IVec3> normal(faces.size());
  std::vector<double> normal_len(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const GridPoint &a = p[faces[f][0]], &b = p[faces[f][1]], &d = p[faces[f][2]];
    normal[f] = cross(sub(b, a), sub(d, a));
    normal_len[f] = length(normal[f]);
  }

  // Feature edges: group the face edges by (min, max) vertex.
  struct EdgeUse {
    std::uint32_t a, b, face;
    bool operator<(const EdgeUse& o) const { return a != o.a ? a < o.a : b != o.b ? b < o.b : face < o.face; }
  };
  std::vector<EdgeUse> uses;
  uses.reserve(faces.size() * 3);
  for (std::uint32_t f = 0; f < faces.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = faces[f][i], b = faces[f][(i + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), f});
    }
  std::sort(uses.begin(), uses.end());
  const double cos_threshold = std::cos(feature_angle_deg * kPi / 180.0);
  std::vector<std::uint32_t> feature_count(n, 0);
  std::vector<std::array<std::uint32_t, 2>> line_nbr(n);
  auto add_feature = [&](std::uint32_t v, std::uint32_t other) {
    if (feature_count[v] < 2) line_nbr[v][feature_count[v]] = other;
    ++feature_count[v];
  };
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].a == uses[i].a && uses[j].b == uses[i].b) ++j;
    bool feature = j - i != 2;
    for (std::size_t k = i; k < j && !feature; ++k) feature = normal_len[uses[k].face] == 0;
    if (!feature) {
      const IVec3 &n1 = normal[uses[i].face], &n2 = normal[uses[i + 1].face];
      const double d = static_cast<double>(n1.x) * static_cast<double>(n2.x) +
                       static_cast<double>(n1.y) * static_cast<double>(n2.y) +
                       static_cast<double>(n1.z) * static_cast<double>(n2.z);
      feature = d < cos_threshold * normal_len[uses[i].face] * normal_len[uses[i + 1].face];
    }
    if (feature) {
      ++r.feature_edges;
      add_feature(uses[i].a, uses[i].b);
      add_feature(uses[i].b, uses[i].a);
    }
    i = j;
  }

  // Incident boundary faces per vertex (ascending face order).
  std::vector<std::uint32_t> first(n + 1, 0), incident(faces.size() * 3);
  for (const auto& f : faces)
    for (std::uint32_t v : f) ++first[v + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::uint32_t f = 0; f < faces.size(); ++f)
      for (std::uint32_t v : faces[f]) incident[fill[v]++] = f;
  }

  std::vector<std::pair<std::uint32_t, std::uint32_t>> spokes;  // (other vertex, local face)
  std::vector<std::uint32_t> parent, ring;
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t begin = first[v], count = first[v + 1] - first[v];
    if (count == 0 || (v < c.boundary.size() && !c.boundary[v])) continue;
    // One edge-connected fan?
    spokes.clear();
    for (std::uint32_t i = 0; i < count; ++i)
      for (std::uint32_t w : faces[incident[begin + i]])
        if (w != v) spokes.emplace_back(w, i);
    std::sort(spokes.begin(), spokes.end());
    parent.resize(count);
    std::iota(parent.begin(), parent.end(), 0u);
    std::uint32_t fans = count;
    for (std::size_t i = 1; i < spokes.size(); ++i)
      if (spokes[i].first == spokes[i - 1].first) {
        const std::uint32_t x = find(parent, spokes[i].second), y = find(parent, spokes[i - 1].second);
        if (x != y) {
          parent[std::max(x, y)] = std::min(x, y);
          --fans;
        }
      }
    const std::uint32_t f = feature_count[v];
    if (fans != 1 || f == 1 || f >= 3) {
      r.type[v] = BoundaryVertexType::corner;
      continue;
    }
    if (f == 2) {
      const GridPoint &a = p[line_nbr[v][0]], &b = p[line_nbr[v][1]];
      const IVec3 d1 = sub(p[v], a), d2 = sub(b, p[v]);
      const double l1 = length(d1), l2 = length(d2);
      if (l1 == 0 || l2 == 0 || static_cast<double>(idot(d1, d2)) < cos_threshold * l1 * l2) {
        r.type[v] = BoundaryVertexType::corner;
        continue;
      }
      r.type[v] = BoundaryVertexType::line;
      r.error[v] = segment_distance(p[v], a, b);
      continue;
    }
    // Simple vertex: plane through the centroid of the boundary neighbours,
    // with the area-weighted normal; numerator exact in integers.
    Vec128 nsum;
    for (std::uint32_t i = 0; i < count; ++i) {
      const IVec3& nf = normal[incident[begin + i]];
      nsum.x += nf.x;
      nsum.y += nf.y;
      nsum.z += nf.z;
    }
    ring.clear();
    for (const auto& s : spokes) ring.push_back(s.first);
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    r.type[v] = BoundaryVertexType::simple;
    const double nlen = length(nsum);
    if (nlen == 0) continue;  // error stays +infinity
    IVec3 w{0, 0, 0};
    for (std::uint32_t u : ring) {
      const IVec3 d = sub(p[v], p[u]);
      w.x += d.x;
      w.y += d.y;
      w.z += d.z;
    }
    const Int128 num = nsum.x * w.x + nsum.y * w.y + nsum.z * w.z;
    r.error[v] = std::fabs(static_cast<double>(num)) / (static_cast<double>(ring.size()) * nlen);
  }
  return r;
}

}  // namespace hmc::detail
