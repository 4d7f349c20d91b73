// SPDX-License-Identifier: AGPL-3.0-or-later
// Classification and decimation of one hierarchy level (thesis §3.2–3.4,
// libhmc/src/encoder/hierarchy/hierarchy.hpp), applied level after level.
//
// Coarser levels for the tests are built here, not by the codec: a volume's
// next level is the Delaunay tetrahedralization of the retained points (the
// inputs are convex, so that is the solid again); a surface's next level
// collapses every removed vertex into one of its (retained) neighbours, the
// one that turns the surrounding triangles least; the rare vertex that no
// collapse can remove validly (link condition, flipped or flat triangles)
// simply stays in the next level. Set HMC_HIERARCHY_REPORT=1
// to print the removal fractions per level.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "delaunay/delaunay.hpp"
#include "encoder/hierarchy/hierarchy.hpp"
#include "encoder/hierarchy/internal.hpp"
#include "hmc/codec.hpp"
#include "samples.hpp"
#include "util/single_faces.hpp"

// hmc::BoundaryMode (public API) and hmc::detail::BoundaryMode share a name:
// only the detail namespace is imported wholesale.
using namespace hmc::detail;
using hmc::GridPoint;
using hmc::Kind;
using hmc::Mesh;
using hmc::Vec3;
namespace samples = hmc::samples;

namespace {

using Tri = std::array<std::uint32_t, 3>;
using Tet = std::array<std::uint32_t, 4>;
constexpr double kPi = 3.14159265358979323846;

bool report() { return std::getenv("HMC_HIERARCHY_REPORT") != nullptr; }

struct TestMesh {
  Kind kind = Kind::surface;
  std::vector<GridPoint> points;
  std::vector<Tri> tris;
  std::vector<Tet> tets;

  LevelMesh view() const {
    LevelMesh m;
    m.points = &points;
    m.triangles = tris;
    m.tetrahedra = tets;
    return m;
  }
};

// ---- Inputs ---------------------------------------------------------------

// Uniform quantization of double points to a grid of 2^bits cells.
std::vector<GridPoint> quantize(const std::vector<Vec3>& pts, int bits) {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& p : pts)
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], p[i]);
      hi[i] = std::max(hi[i], p[i]);
    }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
  const double scale = (std::ldexp(1.0, bits) - 1) / extent;
  std::vector<GridPoint> out;
  for (const auto& p : pts) {
    GridPoint g{};
    for (int i = 0; i < 3; ++i) g[i] = static_cast<std::uint32_t>(std::lround((p[i] - lo[i]) * scale));
    out.push_back(g);
  }
  return out;
}

// A quantized triangle surface: duplicate points merged, degenerate and
// unreferenced ones dropped.
TestMesh surface(const Mesh& m, int bits = 16) {
  const auto q = quantize(m.points, bits);
  std::map<GridPoint, std::uint32_t> id;
  std::vector<std::uint32_t> remap(q.size());
  TestMesh t;
  for (std::size_t i = 0; i < q.size(); ++i) {
    auto it = id.emplace(q[i], static_cast<std::uint32_t>(t.points.size()));
    if (it.second) t.points.push_back(q[i]);
    remap[i] = it.first->second;
  }
  for (const auto& tr : m.triangles) {
    const Tri r{remap[tr[0]], remap[tr[1]], remap[tr[2]]};
    if (r[0] != r[1] && r[1] != r[2] && r[0] != r[2]) t.tris.push_back(r);
  }
  std::vector<std::uint32_t> used(t.points.size(), 0xFFFFFFFFu);
  std::vector<GridPoint> kept;
  for (auto& tr : t.tris)
    for (auto& v : tr) {
      if (used[v] == 0xFFFFFFFFu) {
        used[v] = static_cast<std::uint32_t>(kept.size());
        kept.push_back(t.points[v]);
      }
      v = used[v];
    }
  t.points = kept;
  return t;
}

// The Delaunay tetrahedralization of distinct grid points (canonical order).
TestMesh volume(std::vector<GridPoint> pts) {
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  TestMesh t;
  t.kind = Kind::volume;
  t.points = pts;
  t.tets = delaunay(t.points).tets;
  return t;
}

// Like the thesis' sphere (587 vertices, 247 of them on the boundary): 247
// random points on the unit sphere and 340 inside radius 0.9.
TestMesh thesis_sphere() {
  Mesh shell = samples::random_sphere_points(247, 11);
  const Mesh inside = samples::random_ball(340, 12, 0.9);
  shell.points.insert(shell.points.end(), inside.points.begin(), inside.points.end());
  return volume(quantize(shell.points, 12));
}

TestMesh random_ball(std::size_t n, std::uint64_t seed) {
  return volume(quantize(samples::random_ball(n, seed).points, 12));
}

TestMesh lattice_block(int nx, int ny, int nz) {
  std::vector<GridPoint> p;
  for (const auto& v : samples::lattice(nx, ny, nz, 4.0).points)
    p.push_back({static_cast<std::uint32_t>(v[0]), static_cast<std::uint32_t>(v[1]), static_cast<std::uint32_t>(v[2])});
  return volume(p);
}

// A sphere cut at the equator: an open surface with one circular border.
TestMesh hemisphere() {
  Mesh s = samples::uv_sphere(24, 48);
  Mesh h;
  h.points = s.points;
  for (const auto& t : s.triangles)
    if (s.points[t[0]][2] > -1e-9 && s.points[t[1]][2] > -1e-9 && s.points[t[2]][2] > -1e-9) h.triangles.push_back(t);
  return surface(h);
}

// Triangulated grid of (nx + 1) x (ny + 1) points; `at(i, j)` places them.
template <class F>
TestMesh grid_sheet(int nx, int ny, F at) {
  TestMesh t;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) t.points.push_back(at(i, j));
  auto id = [nx](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      t.tris.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.tris.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return t;
}

// ---- Coarser levels ---------------------------------------------------------

std::array<double, 3> tri_normal(const std::vector<GridPoint>& p, const Tri& t) {
  double a[3], b[3];
  for (int i = 0; i < 3; ++i) {
    a[i] = double(p[t[1]][i]) - double(p[t[0]][i]);
    b[i] = double(p[t[2]][i]) - double(p[t[0]][i]);
  }
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double cosine(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) *
                   std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  return l > 0 ? d / l : -1;
}

// Half-edge collapse of each removed vertex into a neighbour: the link
// condition must hold (a border vertex only slides along a border edge), no
// triangle may flip, and among the valid neighbours the one that turns the
// modified triangles least wins (then the nearer, then the smaller index).
// Vertices that cannot be collapsed stay; their number goes to *stuck.
TestMesh coarsen_surface(const TestMesh& s, const std::vector<std::uint8_t>& removed, std::size_t* stuck) {
  std::vector<Tri> tris = s.tris;
  std::vector<std::uint8_t> alive(tris.size(), 1), gone(s.points.size(), 0);
  auto star = [&](std::uint32_t v) {
    std::vector<std::size_t> r;
    for (std::size_t f = 0; f < tris.size(); ++f)
      if (alive[f] && (tris[f][0] == v || tris[f][1] == v || tris[f][2] == v)) r.push_back(f);
    return r;
  };
  auto edge_faces = [&](const std::vector<std::size_t>& st, std::uint32_t u) {
    std::vector<std::size_t> r;
    for (std::size_t f : st)
      if (tris[f][0] == u || tris[f][1] == u || tris[f][2] == u) r.push_back(f);
    return r;
  };
  auto ring = [&](const std::vector<std::size_t>& st, std::uint32_t v) {
    std::set<std::uint32_t> r;
    for (std::size_t f : st)
      for (std::uint32_t w : tris[f])
        if (w != v) r.insert(w);
    return r;
  };
  for (std::uint32_t v = 0; v < s.points.size(); ++v) {
    if (!removed[v]) continue;
    const auto sv = star(v);
    const auto rv = ring(sv, v);
    bool v_border = false;
    for (std::uint32_t u : rv) v_border |= edge_faces(sv, u).size() == 1;
    double best_cost = 1e300, best_len = 1e300;
    std::uint32_t best = 0xFFFFFFFFu;
    for (std::uint32_t u : rv) {
      const auto shared = edge_faces(sv, u);
      if (v_border && shared.size() != 1) continue;
      std::set<std::uint32_t> opposite;
      for (std::size_t f : shared)
        for (std::uint32_t w : tris[f])
          if (w != u && w != v) opposite.insert(w);
      const auto ru = ring(star(u), u);
      std::size_t common = 0;
      for (std::uint32_t w : rv) common += ru.count(w);
      if (common != opposite.size()) continue;
      double cost = 0;
      bool ok = true;
      for (std::size_t f : sv) {
        if (std::count(shared.begin(), shared.end(), f)) continue;
        Tri t = tris[f];
        for (auto& w : t)
          if (w == v) w = u;
        const double c = cosine(tri_normal(s.points, tris[f]), tri_normal(s.points, t));
        if (!(c > 1e-3)) ok = false;
        cost = std::max(cost, 1 - c);
      }
      if (!ok) continue;
      double len = 0;
      for (int i = 0; i < 3; ++i) len += std::pow(double(s.points[u][i]) - double(s.points[v][i]), 2);
      if (cost < best_cost - 1e-12 || (cost <= best_cost + 1e-12 && len < best_len)) {
        best_cost = cost;
        best_len = len;
        best = u;
      }
    }
    if (best == 0xFFFFFFFFu) {
      if (std::getenv("HMC_HIERARCHY_DEBUG")) {
        std::cerr << "stuck " << v << " border " << v_border << " ring";
        for (std::uint32_t u : rv) std::cerr << " " << u << "(" << edge_faces(sv, u).size() << ")";
        std::cerr << " faces " << sv.size() << "\n";
      }
      ++*stuck;
      continue;
    }
    for (std::size_t f : sv) {
      bool has_u = false;
      for (auto& w : tris[f]) has_u |= w == best;
      if (has_u) {
        alive[f] = 0;
        continue;
      }
      for (auto& w : tris[f])
        if (w == v) w = best;
    }
    gone[v] = 1;
  }
  TestMesh t;
  std::vector<std::uint32_t> remap(s.points.size(), 0xFFFFFFFFu);
  for (std::uint32_t v = 0; v < s.points.size(); ++v)
    if (!gone[v]) {
      remap[v] = static_cast<std::uint32_t>(t.points.size());
      t.points.push_back(s.points[v]);
    }
  for (std::size_t f = 0; f < tris.size(); ++f)
    if (alive[f]) t.tris.push_back({remap[tris[f][0]], remap[tris[f][1]], remap[tris[f][2]]});
  return t;
}

TestMesh coarsen(const TestMesh& m, const std::vector<std::uint8_t>& removed, std::size_t* stuck) {
  if (m.kind == Kind::surface) return coarsen_surface(m, removed, stuck);
  std::vector<GridPoint> kept;
  for (std::size_t v = 0; v < m.points.size(); ++v)
    if (!removed[v]) kept.push_back(m.points[v]);
  return volume(kept);
}

// ---- Invariants ---------------------------------------------------------------

std::vector<std::pair<std::uint32_t, std::uint32_t>> edges(const TestMesh& m) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> e;
  auto add = [&e](std::uint32_t a, std::uint32_t b) { e.emplace_back(std::min(a, b), std::max(a, b)); };
  if (m.kind == Kind::surface)
    for (const auto& t : m.tris)
      for (int i = 0; i < 3; ++i) add(t[i], t[(i + 1) % 3]);
  else
    for (const auto& t : m.tets)
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) add(t[i], t[j]);
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  return e;
}

std::size_t rounded(double r, std::size_t n) { return static_cast<std::size_t>(std::floor(r * double(n) + 0.5)); }

// Checks every documented invariant of one decimation result.
void check_result(const TestMesh& m, const DecimationOptions& o, const DecimationResult& r) {
  const std::size_t n = m.points.size();
  REQUIRE(r.removed.size() == n);
  const auto e = edges(m);
  std::size_t adjacent_pairs = 0;
  for (const auto& [a, b] : e) adjacent_pairs += r.removed[a] && r.removed[b];
  CHECK(adjacent_pairs == 0);  // the independent set

  // Components keep min(size, m) vertices.
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  std::function<std::uint32_t(std::uint32_t)> find = [&](std::uint32_t x) {
    return parent[x] == x ? x : parent[x] = find(parent[x]);
  };
  for (const auto& [a, b] : e) parent[find(a)] = find(b);
  std::map<std::uint32_t, std::pair<std::size_t, std::size_t>> comp;  // root -> (size, kept)
  for (std::uint32_t v = 0; v < n; ++v) {
    auto& c = comp[find(v)];
    ++c.first;
    c.second += !r.removed[v];
  }
  const std::size_t keep = m.kind == Kind::volume ? 4 : 3;
  for (const auto& [root, c] : comp) CHECK(c.second >= std::min(c.first, keep));

  const std::size_t removed = static_cast<std::size_t>(std::count(r.removed.begin(), r.removed.end(), 1));
  std::size_t layer_vertices = 0, layer_removed = 0;
  for (const auto& l : r.layers) {
    layer_vertices += l.vertices;
    layer_removed += l.removed;
  }
  CHECK(layer_vertices == n);
  CHECK(layer_removed == removed);
  CHECK(r.boundary_removed + r.inner_removed == removed);
  CHECK(r.layers[0].vertices == r.classification.boundary_count);
  CHECK(r.layers[0].removed == r.boundary_removed);
  // Budgets.
  const std::size_t boundary = r.classification.boundary_count;
  CHECK(r.boundary_budget == rounded(o.target_ratio, boundary));
  CHECK(r.boundary_removed <= r.boundary_budget);
  CHECK(r.boundary_removed <= r.boundary_candidates);
  if (m.kind == Kind::volume) {
    CHECK(r.inner_budget == rounded(o.target_ratio, n - boundary));
    CHECK(r.inner_removed <= r.inner_budget);
  } else {
    CHECK(r.inner_removed == 0);
    CHECK(r.layers.size() == 1);
  }
  // Removed boundary vertices are candidates: type simple or line, error
  // below Dmax (below Dmax * h(v) / median h in adaptive mode).
  const LevelMesh view = m.view();
  const BoundaryAnalysis a =
      analyze_boundary(view, m.kind, r.classification, vertex_graph(view, m.kind), o.feature_angle_deg);
  std::vector<double> h;
  for (std::uint32_t v = 0; v < n; ++v)
    if ((a.type[v] == BoundaryVertexType::simple || a.type[v] == BoundaryVertexType::line) && a.error[v] < 1e300)
      h.push_back(a.local_length[v]);
  std::sort(h.begin(), h.end());
  const double median = h.empty() ? 0 : h[(h.size() - 1) / 2];
  std::size_t bad = 0;
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!r.removed[v] || !r.classification.boundary[v]) continue;
    bad += a.type[v] != BoundaryVertexType::simple && a.type[v] != BoundaryVertexType::line;
    const double err = o.boundary == BoundaryMode::adaptive ? a.error[v] * median / a.local_length[v] : a.error[v];
    bad += !(err < r.dmax);
  }
  CHECK(bad == 0);
}

std::string mode_name(BoundaryMode b) {
  return b == BoundaryMode::constant ? "constant" : b == BoundaryMode::linear ? "linear" : "adaptive";
}
std::string optimizer_name(InnerOptimizer o, std::uint32_t c = 0) {
  switch (o) {
    case InnerOptimizer::forward: return "forward";
    case InnerOptimizer::backward: return "backward";
    case InnerOptimizer::greedy: return "greedy";
    default: return c ? "central L" + std::to_string(c) : "best";
  }
}

// Decimates `levels` times, checking every level; returns a one-line summary.
std::string run_levels(const std::string& name, TestMesh m, DecimationOptions o, int levels) {
  DecimationState state;
  std::ostringstream line;
  line << std::setw(10) << name << " " << std::setw(8) << mode_name(o.boundary) << " "
       << std::setw(8) << (m.kind == Kind::volume ? optimizer_name(o.optimizer) : std::string("-"))
       << " t=" << o.target_ratio << ":";
  for (int k = 0; k < levels; ++k) {
    INFO(name << ", mode " << mode_name(o.boundary) << ", optimizer " << optimizer_name(o.optimizer) << ", target "
              << o.target_ratio << ", level " << k << ", vertices " << m.points.size());
    o.level = k;
    const DecimationResult r = decimate(m.view(), o, state);
    check_result(m, o, r);
    if (m.kind == Kind::volume) CHECK(r.classification.disagreements == 0);
    const std::size_t removed = r.boundary_removed + r.inner_removed;
    line << " " << m.points.size() << "(-" << std::fixed << std::setprecision(1)
         << 100.0 * double(removed) / double(m.points.size()) << "%";
    if (m.kind == Kind::volume && o.optimizer == InnerOptimizer::best)
      line << " " << optimizer_name(r.chosen, r.central_layer);
    line << ")";
    line.unsetf(std::ios::fixed);
    std::size_t stuck = 0;
    m = coarsen(m, r.removed, &stuck);
    CHECK(stuck <= removed / 20 + 2);  // the test's collapse, not the module, may balk
  }
  return line.str();
}

}  // namespace

// ---------------------------------------------------------------------------

TEST_CASE("classification: every vertex of a surface is a boundary vertex") {
  const TestMesh t = surface(samples::torus(24, 12));
  const Classification c = classify(t.view(), Kind::surface);
  CHECK(c.boundary_count == t.points.size());
  CHECK(std::count(c.boundary.begin(), c.boundary.end(), 1) == std::ptrdiff_t(t.points.size()));
  CHECK(std::count(c.boundary_by_angle.begin(), c.boundary_by_angle.end(), 1) == std::ptrdiff_t(t.points.size()));
  CHECK(c.disagreements == 0);
}

TEST_CASE("classification: faces and solid angles agree on balls and lattice blocks") {
  for (const auto& item : {std::pair<std::string, TestMesh>{"sphere587", thesis_sphere()},
                           {"ball2000", random_ball(2000, 5)},
                           {"lattice9", lattice_block(9, 9, 9)},
                           {"lattice4x7x5", lattice_block(4, 7, 5)}}) {
    const std::string& name = item.first;
    const TestMesh& m = item.second;
    INFO(name);
    const Classification c = classify(m.view(), Kind::volume);
    CHECK(c.disagreements == 0);
    for (std::size_t v = 0; v < m.points.size(); ++v) {
      // Inner vertices: 4π up to rounding; a vertex of the convex hull sees
      // at most a half space.
      if (!c.boundary[v]) CHECK(std::fabs(c.solid_angle[v] - 4 * kPi) < 1e-11);
      if (c.boundary[v]) CHECK(c.solid_angle[v] < 2 * kPi + 1e-11);
    }
    if (name == "lattice9") CHECK(c.boundary_count == std::size_t(9 * 9 * 9 - 7 * 7 * 7));
    if (name == "lattice4x7x5") CHECK(c.boundary_count == std::size_t(4 * 7 * 5 - 2 * 5 * 3));
    if (name == "sphere587") {
      CHECK(m.points.size() == 587);
      CHECK(c.boundary_count >= 247);  // every sphere point is on the hull (a few inner ones may be too)
    }
  }
}

TEST_CASE("classification: a missing tetrahedron opens a cavity") {
  TestMesh m = lattice_block(5, 5, 5);
  // Remove the tetrahedra around the centre vertex: it and its neighbours
  // become boundary vertices by both methods.
  const GridPoint centre{8, 8, 8};
  const auto c_it = std::lower_bound(m.points.begin(), m.points.end(), centre);
  REQUIRE(*c_it == centre);
  const auto ci = static_cast<std::uint32_t>(c_it - m.points.begin());
  CHECK(classify(m.view(), Kind::volume).boundary[ci] == 0);
  const std::size_t centre_degree = vertex_graph(m.view(), Kind::volume).degree(ci);
  m.tets.erase(std::remove_if(m.tets.begin(), m.tets.end(),
                              [ci](const Tet& t) { return std::find(t.begin(), t.end(), ci) != t.end(); }),
               m.tets.end());
  const Classification c = classify(m.view(), Kind::volume);
  CHECK(c.boundary[ci] == 1);  // no tetrahedron left: boundary by convention
  CHECK(c.boundary_by_angle[ci] == 1);
  CHECK(c.disagreements == 0);
  // Boundary now: the 98 outer vertices, the centre, and its neighbours.
  CHECK(c.boundary_count == 98 + 1 + centre_degree);
}

TEST_CASE("Dmax: a flat grid has error 0 inside and keeps its corners") {
  // The plane z = x + 2y + 7 in integers: tilted, so only exact arithmetic
  // gives exactly 0.
  const int N = 12;
  TestMesh sheet = grid_sheet(N, N, [](int i, int j) {
    return GridPoint{std::uint32_t(10 * i), std::uint32_t(10 * j), std::uint32_t(10 * i + 20 * j + 7)};
  });
  const LevelMesh view = sheet.view();
  const Classification c = classify(view, Kind::surface);
  const BoundaryAnalysis a = analyze_boundary(view, Kind::surface, c, vertex_graph(view, Kind::surface));
  std::set<GridPoint> corners;
  for (std::uint32_t v = 0; v < sheet.points.size(); ++v) {
    const int i = int(v) % (N + 1), j = int(v) / (N + 1);
    const bool bi = i == 0 || i == N, bj = j == 0 || j == N;
    INFO("vertex " << i << "," << j);
    if (bi && bj) {
      CHECK(a.type[v] == BoundaryVertexType::corner);
      corners.insert(sheet.points[v]);
    } else if (bi || bj) {
      CHECK(a.type[v] == BoundaryVertexType::line);
      CHECK(a.error[v] == 0.0);
    } else {
      CHECK(a.type[v] == BoundaryVertexType::simple);
      CHECK(a.error[v] == 0.0);
    }
  }
  CHECK(a.feature_edges == std::size_t(4 * N));
  // Maximal decimation, several levels: the corners survive every level;
  // the chosen Dmax admits exactly the zero-error vertices.
  for (BoundaryMode mode : {BoundaryMode::constant, BoundaryMode::linear, BoundaryMode::adaptive}) {
    TestMesh m = sheet;
    DecimationState state;
    DecimationOptions o;
    o.target_ratio = 1.0;
    o.boundary = mode;
    for (int k = 0; k < 5 && m.points.size() > 4; ++k) {
      INFO(mode_name(mode) << " level " << k);
      o.level = k;
      const DecimationResult r = decimate(m.view(), o, state);
      check_result(m, o, r);
      if (k == 0) CHECK(r.boundary_removed > 0);
      if (k == 0) CHECK(r.dmax == std::nextafter(0.0, 1.0));
      CHECK(r.dmax > 0);
      CHECK(r.dmax < 1e-300);
      for (std::uint32_t v = 0; v < m.points.size(); ++v)
        if (corners.count(m.points[v])) CHECK(r.removed[v] == 0);
      std::size_t stuck = 0;
      m = coarsen(m, r.removed, &stuck);
      CHECK(stuck <= r.boundary_removed / 20 + 2);
    }
    std::size_t left = 0;
    for (const auto& p : m.points) left += corners.count(p);
    CHECK(left == 4);
  }
}

TEST_CASE("Dmax errors: distance to the neighbours' plane and to the chord") {
  // A low tent (faces 32° apart, below the feature angle): apex 3 units
  // above a square of four neighbours.
  TestMesh tent;
  tent.points = {{20, 20, 23}, {30, 20, 20}, {20, 30, 20}, {10, 20, 20}, {20, 10, 20}};
  tent.tris = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1}};
  {
    const LevelMesh view = tent.view();
    const BoundaryAnalysis a =
        analyze_boundary(view, Kind::surface, classify(view, Kind::surface), vertex_graph(view, Kind::surface));
    CHECK(a.type[0] == BoundaryVertexType::simple);
    CHECK(a.error[0] == doctest::Approx(3.0));
    for (std::uint32_t v = 1; v <= 4; ++v) CHECK(a.type[v] == BoundaryVertexType::corner);  // 90° turns
  }
  // A flat sheet whose border bulges by 1 unit at one vertex (a turn of
  // about 11°, below the feature angle): a line vertex at distance 1 from
  // the chord of its border neighbours.
  const int N = 4;
  TestMesh sheet = grid_sheet(N, N, [](int i, int j) {
    return GridPoint{std::uint32_t(10 * i), std::uint32_t(10 * j + (i == 2 && j == 0 ? 0 : 1)), 5u};
  });
  const LevelMesh view = sheet.view();
  const BoundaryAnalysis a =
      analyze_boundary(view, Kind::surface, classify(view, Kind::surface), vertex_graph(view, Kind::surface));
  CHECK(a.type[2] == BoundaryVertexType::line);
  CHECK(a.error[2] == doctest::Approx(1.0));
  CHECK(a.error[1] == doctest::Approx(10.0 / std::sqrt(401.0)));  // (10, 1) to the chord (0, 1)-(20, 0)
  CHECK(a.error[N + 2] == 0.0);                                  // flat inside
  CHECK(a.type[0] == BoundaryVertexType::corner);
  // With a 5° feature angle that bulge becomes a corner.
  const BoundaryAnalysis b =
      analyze_boundary(view, Kind::surface, classify(view, Kind::surface), vertex_graph(view, Kind::surface), 5.0);
  CHECK(b.type[2] == BoundaryVertexType::corner);
}

TEST_CASE("Dmax: a folded sheet keeps the corners of its feature line") {
  // A 10 x 12 sheet folded by 90° along j = 6: the fold is a feature line
  // whose two ends (on the border) are corners, as are the sheet's corners.
  const int NX = 10, NY = 12, F = 6;
  TestMesh sheet = grid_sheet(NX, NY, [](int i, int j) {
    return j <= F ? GridPoint{std::uint32_t(8 * i), std::uint32_t(8 * j), 0u}
                  : GridPoint{std::uint32_t(8 * i), std::uint32_t(8 * F), std::uint32_t(8 * (j - F))};
  });
  const LevelMesh view = sheet.view();
  const Classification c = classify(view, Kind::surface);
  const BoundaryAnalysis a = analyze_boundary(view, Kind::surface, c, vertex_graph(view, Kind::surface));
  std::set<GridPoint> corners;
  for (std::uint32_t v = 0; v < sheet.points.size(); ++v) {
    const int i = int(v) % (NX + 1), j = int(v) / (NX + 1);
    const bool bi = i == 0 || i == NX, bj = j == 0 || j == NY;
    INFO("vertex " << i << "," << j);
    if ((bi && bj) || (bi && j == F)) {
      CHECK(a.type[v] == BoundaryVertexType::corner);
      corners.insert(sheet.points[v]);
    } else if (bi || bj || j == F) {
      CHECK(a.type[v] == BoundaryVertexType::line);
      CHECK(a.error[v] == 0.0);
    } else {
      CHECK(a.type[v] == BoundaryVertexType::simple);
      CHECK(a.error[v] == 0.0);
    }
  }
  CHECK(corners.size() == 6);
  CHECK(a.feature_edges == std::size_t(2 * NX + 2 * NY + NX));

  for (BoundaryMode mode : {BoundaryMode::constant, BoundaryMode::linear, BoundaryMode::adaptive}) {
    TestMesh m = sheet;
    DecimationState state;
    DecimationOptions o;
    o.target_ratio = 1.0;
    o.boundary = mode;
    for (int k = 0; k < 5; ++k) {
      INFO(mode_name(mode) << " level " << k);
      o.level = k;
      const DecimationResult r = decimate(m.view(), o, state);
      check_result(m, o, r);
      for (std::uint32_t v = 0; v < m.points.size(); ++v)
        if (corners.count(m.points[v])) CHECK(r.removed[v] == 0);
      std::size_t stuck = 0;
      m = coarsen(m, r.removed, &stuck);
      CHECK(stuck <= r.boundary_removed / 20 + 2);
    }
    std::size_t left = 0;
    for (const auto& p : m.points) left += corners.count(p);
    CHECK(left == 6);
  }
}

TEST_CASE("Dmax modes: constant keeps Dmax0, linear scales it, adaptive picks one per level") {
  TestMesh m = surface(samples::torus(60, 30));
  DecimationState constant, linear;
  DecimationOptions oc, ol;
  oc.target_ratio = ol.target_ratio = 0.2;  // reachable under independence
  oc.boundary = BoundaryMode::constant;
  ol.boundary = BoundaryMode::linear;
  TestMesh mc = m, ml = m;
  for (int k = 0; k < 4; ++k) {
    oc.level = ol.level = k;
    const DecimationResult rc = decimate(mc.view(), oc, constant);
    const DecimationResult rl = decimate(ml.view(), ol, linear);
    CHECK(rc.dmax == constant.dmax0);
    CHECK(rl.dmax == linear.dmax0 * (1 + k));
    if (k == 0) {
      CHECK(constant.dmax0 > 0);
      CHECK(constant.dmax0 == linear.dmax0);
      CHECK(rc.boundary_removed == rc.boundary_budget);
      CHECK(rc.removed == rl.removed);
    }
    // Same level-1 mesh, twice the Dmax: a superset of candidates.
    if (k == 1) CHECK(rl.boundary_candidates >= rc.boundary_candidates);
    std::size_t stuck = 0;
    mc = coarsen(mc, rc.removed, &stuck);
    ml = coarsen(ml, rl.removed, &stuck);
  }
  CHECK(constant.dmax_history.size() == 4);

  DecimationState adaptive;
  DecimationOptions oa;
  oa.target_ratio = 0.2;
  oa.boundary = BoundaryMode::adaptive;
  const DecimationResult ra = decimate(m.view(), oa, adaptive);
  CHECK(adaptive.dmax0 < 0);  // the adaptive mode keeps no Dmax0
  CHECK(ra.boundary_removed == ra.boundary_budget);
}

TEST_CASE("independent sets on every level: surfaces") {
  const std::vector<std::pair<std::string, TestMesh>> meshes = {
      {"sphere", surface(samples::uv_sphere(20, 40))},
      {"torus", surface(samples::torus(48, 24))},
      {"hemisphere", hemisphere()}};
  for (const auto& [name, m] : meshes)
    for (double t : {0.3, 1.0})
      for (BoundaryMode mode : {BoundaryMode::constant, BoundaryMode::linear, BoundaryMode::adaptive}) {
        DecimationOptions o;
        o.kind = Kind::surface;
        o.target_ratio = t;
        o.boundary = mode;
        const std::string line = run_levels(name, m, o, 6);
        if (report()) std::cout << line << "\n";
      }
}

TEST_CASE("independent sets on every level: volumes") {
  const std::vector<std::pair<std::string, TestMesh>> meshes = {{"sphere587", thesis_sphere()},
                                                                {"ball800", random_ball(800, 3)},
                                                                {"lattice8", lattice_block(8, 8, 8)}};
  for (const auto& [name, m] : meshes)
    for (double t : {0.3, 1.0})
      for (BoundaryMode mode : {BoundaryMode::constant, BoundaryMode::linear, BoundaryMode::adaptive})
        for (InnerOptimizer opt :
             {InnerOptimizer::forward, InnerOptimizer::backward, InnerOptimizer::greedy, InnerOptimizer::best}) {
          DecimationOptions o;
          o.kind = Kind::volume;
          o.target_ratio = t;
          o.boundary = mode;
          o.optimizer = opt;
          const std::string line = run_levels(name, m, o, 6);
          if (report()) std::cout << line << "\n";
        }
}

TEST_CASE("layer table of the 587-point sphere (thesis table 4.7)") {
  // VN, CN, L0 ... Ln per level and optimiser, constant Dmax, target 0.3.
  std::ostringstream out;
  for (InnerOptimizer opt : {InnerOptimizer::forward, InnerOptimizer::backward, InnerOptimizer::greedy}) {
    TestMesh m = thesis_sphere();
    DecimationState state;
    DecimationOptions o;
    o.kind = Kind::volume;
    o.optimizer = opt;
    for (int k = 0; k < 4; ++k) {
      o.level = k;
      const DecimationResult r = decimate(m.view(), o, state);
      check_result(m, o, r);
      out << std::setw(9) << optimizer_name(opt) << " level " << k << ": VN " << m.points.size() << " CN "
          << m.tets.size() << " L:";
      std::size_t sum = 0;
      for (const auto& l : r.layers) {
        out << " " << l.vertices << "(-" << l.removed << ")";
        sum += l.vertices;
      }
      CHECK(sum == m.points.size());
      out << " Dmax " << r.dmax << " meanIP " << r.mean_ip_retained << "\n";
      std::size_t stuck = 0;
      m = coarsen(m, r.removed, &stuck);
    }
  }
  if (report()) std::cout << out.str();
}

TEST_CASE("importance: eq. 3.1") {
  CHECK(importance(10, 6, 4, 3) == doctest::Approx(0.4 * 0.25));
  CHECK(importance(10, 10, 4, 1) == 0.0);        // the best-connected vertex
  CHECK(importance(10, 2, 4, 0) == doctest::Approx(0.8));
  CHECK(importance(12, 6, 3, 1) > importance(12, 6, 3, 2));  // deeper: smaller IP
  CHECK(importance(12, 9, 3, 1) < importance(12, 6, 3, 1));  // more neighbours: smaller IP
  CHECK(importance(0, 0, 0, 0) == 0.0);
}

namespace {

// Nested octahedra around a centre: radii 3, 6 and 12 (the outer one is the
// boundary), the gaps between shells filled by triangular prisms split in
// staircase fashion (diagonal from the lower-numbered corner of the inner
// triangle to the higher-numbered corner of the outer one), so the degrees
// vary with the numbering. Layers: outer shell L0, middle L1, inner L2,
// centre L3.
TestMesh nested_octahedra() {
  TestMesh m;
  m.kind = Kind::volume;
  const int dir[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const int oct[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  m.points.push_back({16, 16, 16});  // 0: centre
  for (int r : {3, 6, 12})
    for (const auto& d : dir)
      m.points.push_back({std::uint32_t(16 + r * d[0]), std::uint32_t(16 + r * d[1]), std::uint32_t(16 + r * d[2])});
  auto shell = [](int s, int k) { return std::uint32_t(1 + 6 * s + k); };
  auto add = [&m](Tet t) {
    REQUIRE(canonicalize_tet(m.points, t));
    m.tets.push_back(t);
  };
  for (const auto& f : oct) add({0, shell(0, f[0]), shell(0, f[1]), shell(0, f[2])});
  for (int s = 0; s < 2; ++s)
    for (const auto& f : oct) {
      std::array<int, 3> c{f[0], f[1], f[2]};
      std::sort(c.begin(), c.end());
      const auto a = [&](int i) { return shell(s, c[i]); };
      const auto b = [&](int i) { return shell(s + 1, c[i]); };
      add({a(0), a(1), a(2), b(2)});
      add({a(0), a(1), b(1), b(2)});
      add({a(0), b(0), b(1), b(2)});
    }
  return m;
}

// The labelling the rules of hierarchy.hpp prescribe, computed from scratch:
// groups of inner vertices in the given layer order, each in (IP, index)
// order, greedy independent set; IP by eq. 3.1 in floating point.
std::vector<std::uint8_t> oracle(const TestMesh& m, const std::vector<int>& layer, const std::vector<int>& degree,
                                 const std::vector<std::vector<int>>& groups, std::size_t budget) {
  const auto e = edges(m);
  const int max_degree = *std::max_element(degree.begin(), degree.end());
  const int total = *std::max_element(layer.begin(), layer.end()) + 1;
  std::vector<std::uint8_t> removed(m.points.size(), 0), fixed(m.points.size(), 0);
  std::size_t count = 0;
  for (const auto& g : groups) {
    std::vector<std::uint32_t> vs;
    for (std::uint32_t v = 0; v < m.points.size(); ++v)
      if (std::count(g.begin(), g.end(), layer[v])) vs.push_back(v);
    // IP times MaxDegree * TotalLayers, an integer: exact ties, then index.
    auto key = [&](std::uint32_t v) { return (max_degree - degree[v]) * (total - layer[v]); };
    std::stable_sort(vs.begin(), vs.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
    for (std::uint32_t v : vs) {
      if (fixed[v] || count >= budget) continue;
      removed[v] = 1;
      ++count;
      for (const auto& [a, b] : e) {
        if (a == v) fixed[b] = 1;
        if (b == v) fixed[a] = 1;
      }
    }
  }
  return removed;
}

}  // namespace

TEST_CASE("inner decimation: IP ordering on nested octahedra (deepest, best-connected first)") {
  const TestMesh m = nested_octahedra();
  const LevelMesh view = m.view();
  const Classification c = classify(view, Kind::volume);
  CHECK(c.disagreements == 0);
  CHECK(c.boundary_count == 6);
  const InnerAnalysis a = analyze_inner(vertex_graph(view, Kind::volume), c);
  CHECK(a.total_layers == 4);
  std::vector<int> layer(m.points.size()), degree(m.points.size(), 0);
  for (const auto& [x, y] : edges(m)) {
    ++degree[x];
    ++degree[y];
  }
  for (std::uint32_t v = 0; v < m.points.size(); ++v) {
    layer[v] = v == 0 ? 3 : v <= 6 ? 2 : v <= 12 ? 1 : 0;
    CHECK(a.layer[v] == std::uint32_t(layer[v]));
    CHECK(a.degree[v] == std::uint32_t(degree[v]));
  }
  const int max_degree = *std::max_element(degree.begin(), degree.end());
  CHECK(a.max_degree == std::uint32_t(max_degree));
  for (std::uint32_t v = 0; v < m.points.size(); ++v)
    CHECK(a.ip(v) == doctest::Approx(double(max_degree - degree[v]) / max_degree * double(4 - layer[v]) / 4));
  // Deeper first at equal degree, better connected first in equal layers
  // (eq. 3.1 gives every vertex of maximal degree IP 0, whatever its layer,
  // so those pairs are left out). The example has pairs of both kinds.
  int deeper_pairs = 0, connected_pairs = 0;
  for (std::uint32_t x = 0; x <= 12; ++x)
    for (std::uint32_t y = 0; y <= 12; ++y) {
      if (degree[x] == max_degree || degree[y] == max_degree) continue;
      if (degree[x] == degree[y] && layer[x] > layer[y]) {
        ++deeper_pairs;
        CHECK(a.ip(x) < a.ip(y));
        CHECK(a.key[x] < a.key[y]);
      }
      if (layer[x] == layer[y] && degree[x] > degree[y]) {
        ++connected_pairs;
        CHECK(a.ip(x) < a.ip(y));
        CHECK(a.key[x] < a.key[y]);
      }
    }
  CHECK(deeper_pairs > 0);
  CHECK(connected_pairs > 0);

  // The centre has the fewest neighbours but is deepest; within a shell the
  // better-connected vertices come first.
  const DecimationOptions base = [] {
    DecimationOptions o;
    o.kind = Kind::volume;
    o.target_ratio = 1.0;  // the outer octahedron's vertices are corners: only inner ones go
    return o;
  }();
  const std::size_t budget = 13;
  const std::vector<std::pair<InnerOptimizer, std::vector<std::vector<int>>>> cases = {
      {InnerOptimizer::forward, {{1}, {2}, {3}}},
      {InnerOptimizer::backward, {{3}, {2}, {1}}},
      {InnerOptimizer::greedy, {{1, 2, 3}}}};
  double best_mean = -1;
  InnerOptimizer best = InnerOptimizer::forward;
  std::vector<std::uint8_t> best_removed;
  for (const auto& [opt, groups] : cases) {
    DecimationOptions o = base;
    o.optimizer = opt;
    DecimationState state;
    const DecimationResult r = decimate(view, o, state);
    check_result(m, o, r);
    CHECK(r.boundary_removed == 0);
    CHECK(r.inner_budget == budget);
    CHECK(r.chosen == opt);
    const auto expected = oracle(m, layer, degree, groups, budget);
    CHECK(r.removed == expected);
    double sum = 0;
    int kept = 0;
    for (std::uint32_t v = 0; v <= 12; ++v)
      if (!expected[v]) {
        sum += a.ip(v);
        ++kept;
      }
    const double mean = kept ? sum / kept : 0;
    CHECK(r.mean_ip_retained == doctest::Approx(mean));
    if (mean > best_mean + 1e-12) {
      best_mean = mean;
      best = opt;
      best_removed = expected;
    }
  }
  // Central layer 2: L2, then L3, then L1.
  {
    const auto expected = oracle(m, layer, degree, {{2}, {3}, {1}}, budget);
    double sum = 0;
    int kept = 0;
    for (std::uint32_t v = 0; v <= 12; ++v)
      if (!expected[v]) {
        sum += a.ip(v);
        ++kept;
      }
    if (sum / kept > best_mean + 1e-12) {
      best_mean = sum / kept;
      best = InnerOptimizer::best;
      best_removed = expected;
    }
  }
  DecimationOptions o = base;
  DecimationState state;
  const DecimationResult r = decimate(view, o, state);
  CHECK(r.chosen == best);
  CHECK(r.removed == best_removed);
  CHECK(r.mean_ip_retained == doctest::Approx(best_mean));

  // One removal allowed: it is the inner vertex of smallest IP.
  std::uint32_t first = 0;
  for (std::uint32_t v = 0; v <= 12; ++v)
    if (a.key[v] < a.key[first]) first = v;
  o.optimizer = InnerOptimizer::greedy;
  o.target_ratio = 1.0 / 13;
  state = DecimationState{};
  const DecimationResult one = decimate(view, o, state);
  CHECK(one.inner_removed == 1);
  CHECK(one.removed[first] == 1);
  if (report()) {
    std::cout << "nested octahedra: degree/layer/IP:";
    for (std::uint32_t v = 0; v < 13; ++v)
      std::cout << " " << v << ":" << degree[v] << "/" << layer[v] << "/" << a.ip(v);
    std::cout << "\n  first removed " << first << ", best " << optimizer_name(r.chosen, r.central_layer) << "\n";
  }
}

TEST_CASE("target_ratio is respected") {
  SUBCASE("surfaces: a small target is met exactly") {
    const TestMesh m = surface(samples::torus(48, 24));
    for (double t : {0.05, 0.1, 0.15}) {
      for (BoundaryMode mode : {BoundaryMode::constant, BoundaryMode::adaptive}) {
        DecimationOptions o;
        o.target_ratio = t;
        o.boundary = mode;
        DecimationState state;
        const DecimationResult r = decimate(m.view(), o, state);
        CHECK(r.boundary_removed == rounded(t, m.points.size()));
      }
    }
  }
  SUBCASE("volumes: boundary and inner budgets separately") {
    const TestMesh m = thesis_sphere();
    for (double t : {0.03, 0.06}) {
      DecimationOptions o;
      o.kind = Kind::volume;
      o.target_ratio = t;
      DecimationState state;
      const DecimationResult r = decimate(m.view(), o, state);
      const std::size_t b = r.classification.boundary_count;
      CHECK(r.boundary_removed == rounded(t, b));
      CHECK(r.inner_removed == rounded(t, m.points.size() - b));
    }
  }
  SUBCASE("zero removes nothing") {
    const TestMesh m = thesis_sphere();
    DecimationOptions o;
    o.kind = Kind::volume;
    o.target_ratio = 0;
    DecimationState state;
    const DecimationResult r = decimate(m.view(), o, state);
    CHECK(std::count(r.removed.begin(), r.removed.end(), 1) == 0);
    CHECK(state.dmax0 == 0.0);
  }
}

TEST_CASE("small components and tiny meshes are never emptied") {
  // Two separate tetrahedra and a five-vertex double pyramid.
  TestMesh m;
  m.kind = Kind::volume;
  m.points = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {0, 0, 4},  {20, 0, 0}, {24, 0, 0}, {20, 4, 0},
              {20, 0, 4}, {40, 0, 0}, {44, 0, 0}, {40, 4, 0}, {40, 0, 4}, {43, 3, 3}};
  m.tets = {{0, 1, 2, 3}, {4, 5, 6, 7}, {8, 9, 10, 11}, {9, 10, 11, 12}};
  for (auto& t : m.tets) REQUIRE(canonicalize_tet(m.points, t));
  DecimationOptions o;
  o.kind = Kind::volume;
  o.target_ratio = 1.0;
  DecimationState state;
  const DecimationResult r = decimate(m.view(), o, state);
  check_result(m, o, r);
  for (int v = 0; v < 8; ++v) CHECK(r.removed[v] == 0);
  // A lone triangle surface keeps its three vertices.
  TestMesh s;
  s.points = {{0, 0, 0}, {5, 0, 0}, {0, 5, 0}};
  s.tris = {{0, 1, 2}};
  DecimationOptions os;
  os.target_ratio = 1.0;
  DecimationState ss;
  const DecimationResult rs = decimate(s.view(), os, ss);
  CHECK(std::count(rs.removed.begin(), rs.removed.end(), 1) == 0);
}

TEST_CASE("decimation is deterministic") {
  for (const auto& m : {thesis_sphere(), surface(samples::torus(40, 20)), lattice_block(7, 7, 7)}) {
    for (BoundaryMode mode : {BoundaryMode::constant, BoundaryMode::adaptive}) {
      DecimationOptions o;
      o.kind = m.kind;
      o.boundary = mode;
      DecimationState s1, s2;
      const DecimationResult a = decimate(m.view(), o, s1);
      const DecimationResult b = decimate(m.view(), o, s2);
      CHECK(a.removed == b.removed);
      CHECK(a.dmax == b.dmax);
      CHECK(a.mean_ip_retained == b.mean_ip_retained);
      CHECK(a.chosen == b.chosen);
      CHECK(a.central_layer == b.central_layer);
      CHECK(a.classification.boundary == b.classification.boundary);
      CHECK(a.layers.size() == b.layers.size());
      for (std::size_t k = 0; k < a.layers.size() && k < b.layers.size(); ++k) {
        CHECK(a.layers[k].vertices == b.layers[k].vertices);
        CHECK(a.layers[k].removed == b.layers[k].removed);
      }
      CHECK(s1.dmax0 == s2.dmax0);
    }
  }
}

TEST_CASE("single_faces: the faces whose vertex set occurs once, in ascending order of the sorted triple") {
  // Random faces over few vertices, so that vertex sets repeat (twice, as
  // between two tetrahedra, and more often), in random orientations; and
  // the faces of a Delaunay tetrahedralization, whose single faces are the hull.
  std::mt19937_64 rng(41);
  for (int trial = 0; trial < 50; ++trial) {
    const std::uint32_t n = 4 + static_cast<std::uint32_t>(rng() % 12);
    std::vector<std::array<std::uint32_t, 3>> faces(rng() % 200);
    for (auto& f : faces) {
      do {
        for (auto& v : f) v = static_cast<std::uint32_t>(rng() % n);
      } while (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]);
    }
    // The plain definition: count the sorted triples, keep the single ones
    // with the face as given, ordered by the sorted triple.
    std::map<std::array<std::uint32_t, 3>, std::vector<std::size_t>> uses;
    for (std::size_t i = 0; i < faces.size(); ++i) {
      auto key = faces[i];
      std::sort(key.begin(), key.end());
      uses[key].push_back(i);
    }
    std::vector<std::array<std::uint32_t, 3>> want;
    for (const auto& [key, at] : uses)
      if (at.size() == 1) want.push_back(faces[at[0]]);
    CAPTURE(trial);
    CHECK(single_faces(faces) == want);
  }
  CHECK(single_faces({}).empty());
  const Mesh ball = samples::random_ball(300, 43);
  std::vector<GridPoint> pts;
  for (const auto& p : ball.points)
    pts.push_back({static_cast<std::uint32_t>(512 + 400 * p[0]), static_cast<std::uint32_t>(512 + 400 * p[1]),
                   static_cast<std::uint32_t>(512 + 400 * p[2])});
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  const Tetrahedralization dt = delaunay(pts);
  std::vector<std::array<std::uint32_t, 3>> faces;
  std::size_t hull = 0;
  for (std::size_t t = 0; t < dt.tets.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      faces.push_back({dt.tets[t][(k + 1) & 3], dt.tets[t][(k + 2) & 3], dt.tets[t][(k + 3) & 3]});
      hull += dt.neighbors[t][static_cast<std::size_t>(k)] == kNoTet;
    }
  CHECK(single_faces(faces).size() == hull);

  // A volume level's boundary (hierarchy::boundary_faces, whose faces are
  // made from the tetrahedra as single_faces asks for them): the hull faces
  // of the Delaunay, oriented outward (kFaceVertices), with every third
  // tetrahedron given negatively oriented (its faces flipped back), in
  // ascending order of the sorted triple.
  LevelMesh volume;
  volume.points = &pts;
  volume.tetrahedra = dt.tets;
  for (std::size_t t = 0; t < volume.tetrahedra.size(); t += 3) std::swap(volume.tetrahedra[t][2], volume.tetrahedra[t][3]);
  const auto rotated = [](Tri f) {  // the same oriented face, smallest vertex first
    while (f[0] > f[1] || f[0] > f[2]) f = {f[1], f[2], f[0]};
    return f;
  };
  std::map<Tri, Tri> want;  // sorted triple -> oriented face
  for (std::size_t t = 0; t < dt.tets.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      if (dt.neighbors[t][static_cast<std::size_t>(k)] != kNoTet) continue;
      Tri f;
      for (int i = 0; i < 3; ++i) f[static_cast<std::size_t>(i)] = dt.tets[t][static_cast<std::size_t>(kFaceVertices[k][i])];
      Tri key = f;
      std::sort(key.begin(), key.end());
      want[key] = rotated(f);
    }
  std::vector<std::uint8_t> on;
  const auto got = hierarchy::boundary_faces(volume, Kind::volume, &on);
  REQUIRE(got.size() == want.size());
  std::size_t i = 0;
  for (const auto& [key, face] : want) CHECK(rotated(got[i++]) == face);
  for (const auto& [key, face] : want)
    for (std::uint32_t v : face) CHECK(on[v] == 1);
}
