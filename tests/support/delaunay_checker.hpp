// SPDX-License-Identifier: AGPL-3.0-or-later
//
// An independent certificate checker for the canonical Delaunay
// tetrahedralization (spec/delaunay.md). It shares no code with libhmc's
// delaunay layer: its determinants are computed by the Leibniz formula on
// raw (untranslated) coordinates, and its perturbation is the literal
// definition of spec §3 (the 5x5 lifted determinant as a polynomial in the
// infinitesimal lift offsets), not the orient3d-cofactor shortcut the
// library uses. Slow but obviously right; meant for tests and benchmarks.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "hmc/codec.hpp"

namespace hmc::check {

__extension__ typedef __int128 I128;
using Pt = std::array<std::int64_t, 3>;
using Tet = std::array<std::uint32_t, 4>;

template <int N>
struct Permutations {
  std::vector<std::array<int, N>> perm;
  std::vector<int> sign;
  Permutations() {
    std::array<int, N> p{};
    for (int i = 0; i < N; ++i) p[i] = i;
    do {
      int inv = 0;
      for (int i = 0; i < N; ++i)
        for (int j = i + 1; j < N; ++j) inv += p[i] > p[j];
      perm.push_back(p);
      sign.push_back(inv % 2 ? -1 : 1);
    } while (std::next_permutation(p.begin(), p.end()));
  }
};

/// Determinant by the Leibniz formula (sum over all N! permutations).
/// Callers keep every product of N entries (one per column) below 2^120.
template <int N>
I128 leibniz(const std::array<std::array<I128, N>, N>& m) {
  static const Permutations<N> P;
  I128 sum = 0;
  for (std::size_t k = 0; k < P.perm.size(); ++k) {
    I128 prod = P.sign[k];
    for (int i = 0; i < N && prod != 0; ++i) prod *= m[i][P.perm[k][i]];
    sum += prod;
  }
  return sum;
}

inline int sgn(I128 v) { return (v > 0) - (v < 0); }

/// 6 x signed volume of (a, b, c, d): -det [[a, 1], [b, 1], [c, 1], [d, 1]],
/// positive for a right-handed tetrahedron. Coordinates below 2^24.
inline I128 vol6(const Pt& a, const Pt& b, const Pt& c, const Pt& d) {
  std::array<std::array<I128, 4>, 4> m{};
  const Pt* r[4] = {&a, &b, &c, &d};
  for (int i = 0; i < 4; ++i) m[i] = {(*r[i])[0], (*r[i])[1], (*r[i])[2], 1};
  return -leibniz<4>(m);
}

/// The lifted 5x5 determinant with rows (x, y, z, lift, 1). `lift_override`
/// >= 0 replaces the lift column by the unit vector at that row.
inline I128 lifted(const std::array<Pt, 5>& p, int lift_override = -1) {
  std::array<std::array<I128, 5>, 5> m{};
  for (int i = 0; i < 5; ++i) {
    const I128 l = static_cast<I128>(p[i][0]) * p[i][0] + static_cast<I128>(p[i][1]) * p[i][1] +
                   static_cast<I128>(p[i][2]) * p[i][2];
    m[i] = {p[i][0], p[i][1], p[i][2], lift_override < 0 ? l : (i == lift_override ? 1 : 0), 1};
  }
  return leibniz<5>(m);
}

/// Sign of the lifted determinant with lifts |p|^2 - eps_rank, eps_0 >> eps_1
/// >> ... (spec §3), for points p[0..4] whose canonical indices are rank[].
/// For a right-handed (a, b, c, d), negative iff e is inside the perturbed
/// sphere, positive iff outside.
inline int lifted_perturbed(const std::array<Pt, 5>& p, const std::array<std::uint32_t, 5>& rank,
                            bool* unperturbed_zero = nullptr) {
  const I128 d = lifted(p);
  if (unperturbed_zero) *unperturbed_zero = d == 0;
  if (d != 0) return sgn(d);
  // d(eps) = d + sum_r (coefficient of eps_rank[r]) * eps_rank[r], where the
  // coefficient is the determinant with the lift column replaced by -e_r.
  std::array<int, 5> order{0, 1, 2, 3, 4};
  std::sort(order.begin(), order.end(), [&](int x, int y) { return rank[x] < rank[y]; });
  for (int r : order) {
    const I128 c = -lifted(p, r);
    if (c != 0) return sgn(c);
  }
  return 0;
}

inline Pt to_pt(const GridPoint& g) { return {g[0], g[1], g[2]}; }

/// True if the points span 3D.
inline bool spans_3d(const std::vector<GridPoint>& g) {
  for (std::size_t i = 0; i < g.size(); ++i)
    for (std::size_t j = i + 1; j < g.size(); ++j)
      for (std::size_t k = j + 1; k < g.size(); ++k) {
        // Find one non-collinear triple, then test every fourth point.
        const Pt a = to_pt(g[i]), b = to_pt(g[j]), c = to_pt(g[k]);
        const Pt u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const bool collinear =
            u[1] * v[2] == u[2] * v[1] && u[2] * v[0] == u[0] * v[2] && u[0] * v[1] == u[1] * v[0];
        if (collinear) continue;
        for (const auto& q : g)
          if (vol6(a, b, c, to_pt(q)) != 0) return true;
        return false;
      }
  return false;
}

struct Report {
  bool ok = true;
  std::string error;
  std::size_t interior_faces = 0;
  std::size_t hull_faces = 0;
  std::size_t cospherical_faces = 0;  ///< interior faces whose unperturbed test is a tie
  std::size_t tie_tets = 0;           ///< tetrahedra with at least one such face
};

/// Verifies that `tets` is the canonical Delaunay tetrahedralization of
/// `g` (distinct points in canonical order). `plane_check` enables the
/// O(n * hull faces) test that every point lies on or behind every hull face.
inline Report check_delaunay(const std::vector<GridPoint>& g, const std::vector<Tet>& tets,
                             bool plane_check = true) {
  Report r;
  auto bad = [&](std::string m) {
    r.ok = false;
    r.error = std::move(m);
    return r;
  };
  std::vector<Pt> p(g.size());
  for (std::size_t i = 0; i < g.size(); ++i) p[i] = to_pt(g[i]);
  if (g.size() < 4 || !spans_3d(g)) return tets.empty() ? r : bad("tetrahedra for a degenerate set");
  if (tets.empty()) return bad("no tetrahedra");

  // Canonical form and order; positive orientation.
  I128 volume = 0;
  std::vector<char> used(g.size(), 0);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const Tet& T = tets[t];
    for (auto v : T)
      if (v >= g.size()) return bad("index out of range");
    if (!(T[0] < T[1] && T[1] < T[2] && T[1] < T[3] && T[2] != T[3])) return bad("tet not in canonical form");
    if (t > 0 && !(tets[t - 1] < T)) return bad("tets not strictly sorted");
    const I128 v = vol6(p[T[0]], p[T[1]], p[T[2]], p[T[3]]);
    if (v <= 0) return bad("tet not positively oriented");
    volume += v;
    for (auto x : T) used[x] = 1;
  }
  for (auto u : used)
    if (!u) return bad("a point is not a vertex");

  // Faces: sorted triple -> (tet, apex) list.
  std::map<std::array<std::uint32_t, 3>, std::vector<std::pair<std::uint32_t, std::uint32_t>>> faces;
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<std::uint32_t, 3> f{};
      for (int i = 0, m = 0; i < 4; ++i)
        if (i != k) f[m++] = tets[t][i];
      std::sort(f.begin(), f.end());
      faces[f].push_back({static_cast<std::uint32_t>(t), tets[t][k]});
    }
  std::vector<std::array<std::uint32_t, 4>> hull;  // outward face + apex
  std::vector<char> tie_tet(tets.size(), 0);
  for (const auto& [f, inc] : faces) {
    if (inc.size() > 2) return bad("face in more than two tets");
    if (inc.size() == 2) {
      ++r.interior_faces;
      const int s1 = sgn(vol6(p[f[0]], p[f[1]], p[f[2]], p[inc[0].second]));
      const int s2 = sgn(vol6(p[f[0]], p[f[1]], p[f[2]], p[inc[1].second]));
      if (s1 * s2 != -1) return bad("interior face with both tets on one side");
      for (int side = 0; side < 2; ++side) {
        const Tet& T = tets[inc[side].first];
        const std::uint32_t e = inc[1 - side].second;
        bool tie = false;
        const int s = lifted_perturbed({p[T[0]], p[T[1]], p[T[2]], p[T[3]], p[e]}, {T[0], T[1], T[2], T[3], e}, &tie);
        if (s <= 0) return bad("interior face not locally Delaunay under the perturbation");
        if (tie && side == 0) {
          ++r.cospherical_faces;
          tie_tet[inc[0].first] = tie_tet[inc[1].first] = 1;
        }
      }
    } else {
      ++r.hull_faces;
      std::array<std::uint32_t, 4> h{f[0], f[1], f[2], inc[0].second};
      if (vol6(p[h[0]], p[h[1]], p[h[2]], p[h[3]]) > 0) std::swap(h[1], h[2]);  // outward
      hull.push_back(h);
    }
  }
  for (auto x : tie_tet) r.tie_tets += static_cast<std::size_t>(x);

  // Hull: closed (every edge in two hull faces), coplanar neighbours obey
  // the rule, every point on or behind every hull plane, and the volume.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::size_t>> edges;
  I128 hull_volume = 0;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const auto& h = hull[i];
    for (int k = 0; k < 3; ++k) edges[{std::min(h[k], h[(k + 1) % 3]), std::max(h[k], h[(k + 1) % 3])}].push_back(i);
    hull_volume += vol6(p[0], p[h[0]], p[h[1]], p[h[2]]);
    if (plane_check)
      for (const auto& q : p)
        if (vol6(p[h[0]], p[h[1]], p[h[2]], q) > 0) return bad("a point lies outside a hull face's plane");
  }
  for (const auto& [e, fs] : edges) {
    if (fs.size() != 2) return bad("hull surface not closed");
    for (int side = 0; side < 2; ++side) {
      const auto& F = hull[fs[side]];
      const auto& G = hull[fs[1 - side]];
      std::uint32_t w = G[0];
      for (int k = 0; k < 3; ++k)
        if (G[k] != e.first && G[k] != e.second) w = G[k];
      const I128 o = vol6(p[F[0]], p[F[1]], p[F[2]], p[w]);
      if (o > 0) return bad("hull not convex at an edge");
      if (o == 0) {
        // Coplanar hull neighbours: w must lie outside the perturbed sphere
        // of F's tetrahedron (the 2D rule restricted to the hull plane).
        Tet T{F[0], F[2], F[1], F[3]};  // inward face + apex: right-handed
        if (lifted_perturbed({p[T[0]], p[T[1]], p[T[2]], p[T[3]], p[w]}, {T[0], T[1], T[2], T[3], w}) <= 0)
          return bad("coplanar hull faces violate the rule");
      }
    }
  }
  if (hull_volume != volume) return bad("tet volumes do not add up to the hull volume");

  // Coverage multiplicity: the centroid of a few tets lies in no other tet.
  const std::size_t samples = std::min<std::size_t>(tets.size(), 12);
  for (std::size_t s = 0; s < samples; ++s) {
    const std::size_t t = s * (tets.size() - 1) / std::max<std::size_t>(samples - 1, 1);
    Pt c{0, 0, 0};
    for (auto v : tets[t])
      for (int a = 0; a < 3; ++a) c[a] += p[v][a];
    for (std::size_t u = 0; u < tets.size(); ++u) {
      if (u == t) continue;
      Pt q[4];
      for (int k = 0; k < 4; ++k)
        for (int a = 0; a < 3; ++a) q[k][a] = 4 * p[tets[u][k]][a];
      bool inside = vol6(c, q[1], q[2], q[3]) >= 0 && vol6(q[0], c, q[2], q[3]) >= 0 &&
                    vol6(q[0], q[1], c, q[3]) >= 0 && vol6(q[0], q[1], q[2], c) >= 0;
      if (inside) return bad("tets overlap");
    }
  }
  return r;
}

/// The canonical tetrahedralization by definition (spec §3): every
/// non-flat 4-subset whose perturbed circumsphere has every other point
/// strictly outside. O(n^5); for small n only. Canonical form and order.
inline std::vector<Tet> brute_force(const std::vector<GridPoint>& g) {
  std::vector<Tet> out;
  const auto n = static_cast<std::uint32_t>(g.size());
  for (std::uint32_t a = 0; a < n; ++a)
    for (std::uint32_t b = a + 1; b < n; ++b)
      for (std::uint32_t c = b + 1; c < n; ++c)
        for (std::uint32_t d = c + 1; d < n; ++d) {
          Tet T{a, b, c, d};
          const I128 v = vol6(to_pt(g[a]), to_pt(g[b]), to_pt(g[c]), to_pt(g[d]));
          if (v == 0) continue;
          if (v < 0) std::swap(T[2], T[3]);
          bool empty = true;
          for (std::uint32_t e = 0; e < n && empty; ++e) {
            if (e == a || e == b || e == c || e == d) continue;
            empty = lifted_perturbed({to_pt(g[T[0]]), to_pt(g[T[1]]), to_pt(g[T[2]]), to_pt(g[T[3]]), to_pt(g[e])},
                                     {T[0], T[1], T[2], T[3], e}) > 0;
          }
          if (empty) out.push_back(T);
        }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace hmc::check
