// SPDX-License-Identifier: AGPL-3.0-or-later
// Backend-independent part of the canonical Delaunay layer: input checks,
// the degenerate cases, the canonical form, and the certificate that every
// backend's output must pass (spec/delaunay.md §5–6).
#include "delaunay/delaunay.hpp"

#include <algorithm>

#include "delaunay/adjacency.hpp"
#include "delaunay/predicates.hpp"
#include "util/error.hpp"

namespace hmc::detail {

namespace {

constexpr std::uint32_t kCoordLimit = std::uint32_t{1} << 21;

bool less_canonical(const GridPoint& a, const GridPoint& b) {
  return a[0] != b[0] ? a[0] < b[0] : a[1] != b[1] ? a[1] < b[1] : a[2] < b[2];
}

// True if the points span 3D, i.e. some four of them are not coplanar.
bool spans_3d(const std::vector<GridPoint>& p) {
  const std::size_t n = p.size();
  if (n < 4) return false;
  // p[0] != p[1] (distinct points). Find a point off the line p0 p1.
  const IVec3 u = sub(p[1], p[0]);
  std::size_t i2 = 2;
  for (; i2 < n; ++i2) {
    const IVec3 v = sub(p[i2], p[0]);
    if (u.y * v.z - u.z * v.y != 0 || u.z * v.x - u.x * v.z != 0 || u.x * v.y - u.y * v.x != 0) break;
  }
  if (i2 == n) return false;
  for (std::size_t i3 = 2; i3 < n; ++i3)
    if (orient3d(p[0], p[1], p[i2], p[i3]) != 0) return true;
  return false;
}

using TetList = std::vector<std::array<std::uint32_t, 4>>;

// Sorts canonical tetrahedra lexicographically, carrying their neighbour
// lists along (if any): a counting sort on the first vertex, then an
// insertion sort of each bucket (about 7 tetrahedra on average).
void sort_tets(TetList& tets, TetList& nb, std::size_t num_points) {
  struct Rec {
    std::array<std::uint32_t, 4> v, n;
    std::uint32_t old;
  };
  const std::size_t nt = tets.size();
  const bool with_nb = !nb.empty();
  std::vector<std::uint32_t> start(num_points + 1, 0);
  for (const auto& t : tets) ++start[t[0] + 1];
  for (std::size_t i = 0; i < num_points; ++i) start[i + 1] += start[i];
  std::vector<Rec> rec(nt);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      rec[fill[tets[t][0]]++] = {tets[t], with_nb ? nb[t] : std::array<std::uint32_t, 4>{}, static_cast<std::uint32_t>(t)};
  }
  auto before = [](const Rec& a, const Rec& b) { return a.v < b.v; };
  for (std::size_t a = 0; a < num_points; ++a) {
    Rec* lo = rec.data() + start[a];
    Rec* hi = rec.data() + start[a + 1];
    if (hi - lo > 32) {
      std::sort(lo, hi, before);
      continue;
    }
    for (Rec* i = lo + 1; i < hi; ++i)
      for (Rec* j = i; j > lo && before(*j, j[-1]); --j) std::swap(j[-1], *j);
  }
  std::vector<std::uint32_t> where(with_nb ? nt : 0);
  for (std::size_t i = 0; i < nt; ++i) {
    tets[i] = rec[i].v;
    if (with_nb) where[rec[i].old] = static_cast<std::uint32_t>(i);
  }
  if (!with_nb) return;
  for (std::size_t i = 0; i < nt; ++i)
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = rec[i].n[k];
      nb[i][k] = u < nt ? where[u] : kNoTet;
    }
}

// The checks of certificate_error() on tetrahedra in canonical vertex order
// (list in any order) with their claimed adjacency, which is verified too.
std::string check(const std::vector<GridPoint>& pts, const TetList& tets, const TetList& nb,
                  HelperBudget* helpers = nullptr) {
  const std::size_t nt = tets.size();
  if (nb.size() != nt) return "no adjacency";

  // Interior faces: the twin face has the same vertices in the opposite
  // orientation (so the apexes lie on opposite sides), and is locally
  // Delaunay under the perturbed test. Each pair is examined once, from its
  // smaller tetrahedron; counting shows that every link is reciprocated.
  // A tetrahedron and its neighbours share one cache line: the loop below
  // visits neighbours in no particular memory order.
  struct alignas(32) Cell {
    std::array<std::uint32_t, 4> v, n;
  };
  std::vector<Cell> cells(nt);
  for (std::size_t t = 0; t < nt; ++t) cells[t] = {tets[t], nb[t]};
  // The tetrahedra [begin, end): the first failure among them, links and
  // pairs counted. Two ranges may run on two threads; the first range's
  // failure is the one a single pass would meet first.
  struct Part {
    std::string error;
    std::size_t links = 0, pairs = 0;
  };
  auto faces = [&](std::size_t begin, std::size_t end, Part& part) {
    constexpr std::size_t kAhead = 6;
    for (std::size_t t = begin; t < end; ++t) {
      if (t + kAhead < end)
        for (std::uint32_t w : cells[t + kAhead].n)
          if (w != kNoTet && w < nt) __builtin_prefetch(&cells[w]);
      const auto& T = cells[t].v;
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t u = cells[t].n[k];
        if (u == kNoTet) continue;
        ++part.links;
        if (u < t) continue;
        if (u >= nt || u == t) return void(part.error = "bad adjacency");
        const Cell& C = cells[u];
        int j = 0;
        while (j < 4 && C.n[j] != t) ++j;
        if (j == 4) return void(part.error = "asymmetric adjacency");
        const auto& U = C.v;
        const int* f = kFaceVertices[k];
        const int* g = kFaceVertices[j];
        int i = 0;
        while (i < 3 && U[g[i]] != T[f[0]]) ++i;
        if (i == 3 || U[g[(i + 1) % 3]] != T[f[2]] || U[g[(i + 2) % 3]] != T[f[1]])
          return void(part.error = "neighbours do not share a face in opposite orientations");
        if (insphere_perturbed(pts, {T[0], T[1], T[2], T[3], U[j]}) >= 0)
          return void(part.error = "face not locally Delaunay: tet " + std::to_string(t) + ", point " +
                                   std::to_string(U[j]));
        ++part.pairs;
      }
    }
  };
  Part first, second;
  split_range(helpers, nt, 16384,
              [&](std::size_t begin, std::size_t end) { faces(begin, end, begin == 0 ? first : second); });
  if (!first.error.empty()) return first.error;
  if (!second.error.empty()) return second.error;
  if (first.links + second.links != 2 * (first.pairs + second.pairs)) return "asymmetric adjacency";

  // Hull: a closed, connected, locally convex surface with Euler
  // characteristic 2, and every point a vertex.
  const auto hull = hull_faces(tets, nb);
  struct DirEdge {
    std::uint64_t key;  // (from << 32) | to
    std::uint32_t face;
  };
  std::vector<DirEdge> edges;
  edges.reserve(3 * hull.size());
  for (std::size_t f = 0; f < hull.size(); ++f)
    for (int i = 0; i < 3; ++i)
      edges.push_back({(static_cast<std::uint64_t>(hull[f].v[i]) << 32) | hull[f].v[(i + 1) % 3],
                       static_cast<std::uint32_t>(f)});
  std::sort(edges.begin(), edges.end(), [](const DirEdge& a, const DirEdge& b) { return a.key < b.key; });
  std::vector<std::uint32_t> parent(hull.size());
  for (std::size_t f = 0; f < hull.size(); ++f) parent[f] = static_cast<std::uint32_t>(f);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t i = 0; i < edges.size(); ++i) {
    if (i + 1 < edges.size() && edges[i + 1].key == edges[i].key) return "hull edge used twice in one direction";
    const std::uint64_t twin = (edges[i].key << 32) | (edges[i].key >> 32);
    auto it = std::lower_bound(edges.begin(), edges.end(), twin,
                               [](const DirEdge& a, std::uint64_t k) { return a.key < k; });
    if (it == edges.end() || it->key != twin) return "hull surface not closed";
    const auto& F = hull[edges[i].face].v;
    const auto& G = hull[it->face].v;
    const std::uint32_t from = static_cast<std::uint32_t>(twin & 0xFFFFFFFFu);
    const std::uint32_t to = static_cast<std::uint32_t>(twin >> 32);
    std::uint32_t w = G[0];
    for (std::uint32_t g : G)
      if (g != from && g != to) w = g;
    if (orient3d(pts[F[0]], pts[F[1]], pts[F[2]], pts[w]) > 0) return "hull not convex";
    parent[find(edges[i].face)] = find(it->face);
  }
  std::vector<char> on_hull(pts.size(), 0), used(pts.size(), 0);
  std::size_t hull_vertices = 0;
  for (const auto& f : hull)
    for (std::uint32_t v : f.v)
      if (!on_hull[v]) on_hull[v] = 1, ++hull_vertices;
  for (std::size_t f = 1; f < hull.size(); ++f)
    if (find(static_cast<std::uint32_t>(f)) != find(0)) return "hull surface not connected";
  if (hull_vertices + hull.size() != edges.size() / 2 + 2) return "hull surface is not a sphere";
  for (const auto& T : tets)
    for (std::uint32_t v : T) used[v] = 1;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (!used[i]) return "point " + std::to_string(i) + " is not a vertex";
  return {};
}

// Puts a backend's output in canonical form and order (with its adjacency,
// building it if the backend gave none) and checks it.
std::string verify_backend_output(const std::vector<GridPoint>& pts, TetList& tets, TetList& nb,
                                  HelperBudget* helpers = nullptr) {
  if (tets.empty()) return "the backend failed";
  if (!nb.empty() && nb.size() != tets.size()) return "bad adjacency size";
  for (std::size_t t = 0; t < tets.size(); ++t) {
    auto& T = tets[t];
    for (std::uint32_t v : T)
      if (v >= pts.size()) return "vertex index out of range";
    // Sort the four vertices, permuting the neighbour slots alongside.
    std::array<std::uint32_t, 4> n = nb.empty() ? std::array<std::uint32_t, 4>{} : nb[t];
    for (int i = 1; i < 4; ++i)
      for (int j = i; j > 0 && T[j] < T[j - 1]; --j) std::swap(T[j], T[j - 1]), std::swap(n[j], n[j - 1]);
    const int o = orient3d(pts[T[0]], pts[T[1]], pts[T[2]], pts[T[3]]);
    if (o == 0) return "flat tetrahedron";
    if (o < 0) std::swap(T[2], T[3]), std::swap(n[2], n[3]);
    if (!nb.empty()) nb[t] = n;
  }
  std::string err;
  if (nb.empty()) {
    sort_tets(tets, nb, pts.size());
    if (!build_adjacency(tets, pts.size(), nb, &err)) return err;
    err = check(pts, tets, nb, helpers);
  } else {
    err = check(pts, tets, nb, helpers);  // before sorting: the backend's order is more local
    sort_tets(tets, nb, pts.size());
  }
  if (!err.empty()) return err;
  for (std::size_t t = 1; t < tets.size(); ++t)
    if (tets[t] == tets[t - 1]) return "duplicate tetrahedron";
  return {};
}

}  // namespace

bool canonicalize_tet(const std::vector<GridPoint>& points, std::array<std::uint32_t, 4>& t) {
  std::sort(t.begin(), t.end());
  const int o = orient3d(points[t[0]], points[t[1]], points[t[2]], points[t[3]]);
  if (o < 0) std::swap(t[2], t[3]);
  return o != 0;
}

std::string certificate_error(const std::vector<GridPoint>& points, const TetList& tets) {
  if (!spans_3d(points)) return tets.empty() ? std::string{} : "tetrahedra for a degenerate point set";
  if (tets.empty()) return "no tetrahedra";
  auto canon = tets;
  for (auto& t : canon) {
    for (std::uint32_t v : t)
      if (v >= points.size()) return "vertex index out of range";
    if (!canonicalize_tet(points, t)) return "flat tetrahedron";
  }
  TetList nb;
  sort_tets(canon, nb, points.size());
  for (std::size_t t = 1; t < canon.size(); ++t)
    if (canon[t] == canon[t - 1]) return "duplicate tetrahedron";
  std::string err;
  if (!build_adjacency(canon, points.size(), nb, &err)) return err;
  return check(points, canon, nb);
}

std::uint64_t max_delaunay_tets(std::uint64_t n) {
  if (n < 4) return 0;
  if (n > (std::uint64_t{1} << 32)) return ~std::uint64_t{0};
  return n * (n - 3) / 2;
}

namespace {

void check_input(const std::vector<GridPoint>& points) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    if (p[0] >= kCoordLimit || p[1] >= kCoordLimit || p[2] >= kCoordLimit)
      fail(Status::internal_error, "delaunay: coordinate out of range at point " + std::to_string(i));
    if (i > 0 && !less_canonical(points[i - 1], p))
      fail(Status::internal_error, "delaunay: points not distinct and in canonical order at " + std::to_string(i));
  }
  if (points.size() > (std::size_t{1} << 28)) fail(Status::internal_error, "delaunay: too many points");
}

// The cell cap of the native backend for at most max_tets tetrahedra.
std::uint64_t native_cap(std::size_t n, std::uint64_t max_tets) {
  const std::uint64_t hull = 2 * static_cast<std::uint64_t>(n) + 8;  // hull faces: at most 2n - 4
  return max_tets > ~std::uint64_t{0} - hull ? ~std::uint64_t{0} : max_tets + hull;
}

}  // namespace

Tetrahedralization delaunay_refine(const std::vector<GridPoint>& points, const std::vector<GridPoint>& sub_points,
                                   Tetrahedralization&& sub, std::uint64_t max_tets, HelperBudget* helpers) {
  if (sub.tets.empty()) {
    sub = {};
    return delaunay(points, max_tets, helpers);
  }
  check_input(points);
  // Position of each subset point in `points` (both ascending).
  std::vector<std::uint32_t> index(sub_points.size());
  std::size_t j = 0;
  for (std::size_t i = 0; i < sub_points.size(); ++i) {
    while (j < points.size() && less_canonical(points[j], sub_points[i])) ++j;
    if (j == points.size() || points[j] != sub_points[i])
      fail(Status::internal_error, "delaunay: the coarser points are not a subset at " + std::to_string(i));
    index[i] = static_cast<std::uint32_t>(j++);
  }
  TetList tets, nb;
  backend::native_refine(points, index, sub.tets, sub.neighbors, tets, nb, native_cap(points.size(), max_tets));
  const std::string error = verify_backend_output(points, tets, nb, helpers);
  if (!error.empty()) fail(Status::internal_error, "delaunay: refining a tetrahedralization failed: " + error);
  Tetrahedralization out;
  out.tets = std::move(tets);
  out.neighbors = std::move(nb);
  return out;
}

Tetrahedralization delaunay(const std::vector<GridPoint>& points, std::uint64_t max_tets, HelperBudget* helpers) {
  check_input(points);
  Tetrahedralization out;
  if (!spans_3d(points)) return out;

  TetList tets, nb;
  std::string error = "TetGen not applicable";
  const bool bounded = max_delaunay_tets(points.size()) <= max_tets;
  if (!bounded) error = "TetGen not run: its worst case exceeds the limit of " + std::to_string(max_tets) + " tetrahedra";
  if (bounded && backend::tetgen(points, tets, nb)) {
    error = verify_backend_output(points, tets, nb, helpers);
    if (error.empty()) {
      out.tets = std::move(tets);
      out.neighbors = std::move(nb);
      return out;
    }
  }
  tets.clear();
  nb.clear();
  backend::native(points, tets, nb, native_cap(points.size(), max_tets));
  const std::string native_error = verify_backend_output(points, tets, nb, helpers);
  if (!native_error.empty())
    fail(Status::internal_error, "delaunay: no backend produced a verified tetrahedralization (TetGen: " + error +
                                     "; native: " + native_error + ")");
  out.tets = std::move(tets);
  out.neighbors = std::move(nb);
  return out;
}

}  // namespace hmc::detail
