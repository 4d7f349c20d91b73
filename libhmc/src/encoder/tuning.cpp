// SPDX-License-Identifier: AGPL-3.0-or-later
#include "encoder/tuning.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <set>

#include "entropy/rice.hpp"
#include "encoder/distance.hpp"
#include "encoder/winding.hpp"
#include "util/morton.hpp"
#include "util/radix_sort.hpp"

namespace hmc::detail {

std::pair<std::size_t, long> interface_topology(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside);

namespace {

using Face = std::array<std::uint32_t, 3>;

Face sorted(Face f) {
  std::sort(f.begin(), f.end());
  return f;
}

// Bits to send a sorted list of `count` indices out of `range` as gaps.
std::uint64_t list_bits(std::uint64_t count, std::uint64_t range) {
  if (count == 0) return 8;
  const double gap = static_cast<double>(range) / static_cast<double>(count);
  return static_cast<std::uint64_t>(static_cast<double>(count) * (std::log2(gap + 1) + 2.0)) + 8;
}

// The toggle lists of `toggled` (ascending) under the labels `inside`: in
// the label contexts or, where shorter, the candidate contexts, with or
// without the vertex contexts (spec 11.5; 80 empty lists cost 72 bits more
// than 8).
// Or, where shorter still, in the neighbour contexts (flag bit 7), each
// list naming the toggled tetrahedra of its context or, where fewer bits,
// the others.
struct ToggleCoding {
  std::array<std::vector<std::uint32_t>, kToggleContexts> ranks;
  bool by_candidates = false, by_vertices = false, by_neighbours = false;
  std::vector<std::vector<std::uint32_t>> lists;  // by_neighbours
  std::vector<std::uint8_t> inverted;             // by_neighbours
  std::uint64_t bits = 0;
};

// The neighbour contexts' lists of `toggled` from the 80 contexts `ctx`, and
// their bits.
ToggleCoding code_by_neighbours(const Tetrahedralization& dt, const std::vector<std::uint8_t>& ctx,
                                const std::vector<std::uint32_t>& toggled) {
  auto nr = neighbour_ranks(dt, ctx, toggled);
  ToggleCoding out;
  out.by_candidates = out.by_vertices = out.by_neighbours = true;
  out.lists = std::move(nr.ranks);
  out.inverted.assign(kNeighbourContexts, 0);
  for (std::size_t j = 0; j < kNeighbourContexts; ++j) {
    auto& list = out.lists[j];
    const std::uint64_t bits = rice_list_bits(list, 2 * list.size());
    // The other tetrahedra of the context, where they are fewer.
    if (2 * list.size() > nr.sizes[j]) {
      std::vector<std::uint32_t> others;
      others.reserve(nr.sizes[j] - list.size());
      std::size_t i = 0;
      for (std::uint32_t r = 0; r < nr.sizes[j]; ++r) {
        if (i < list.size() && list[i] == r) ++i;
        else others.push_back(r);
      }
      const std::uint64_t other_bits = rice_list_bits(others, 2 * others.size() + 1);
      if (other_bits < bits) {
        list.swap(others);
        out.inverted[j] = 1;
        out.bits += other_bits;
        continue;
      }
    }
    out.bits += bits;
  }
  return out;
}

// `neighbours`: whether to try the neighbour contexts too. The tuning's
// trials price the mismatches without them: the toggles finally sent are
// fewer (fidelity shape leaves thin mismatches to the rule) and cluster
// less: pricing the trials' clusters as cheap picked parameters that made
// the one-level streams of the horse and the Stanford bunny 1.3 and 1.9 %
// larger (the skull's 0.4 % smaller than pricing them without).
ToggleCoding code_toggles(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside,
                          const std::vector<std::uint32_t>& toggled, const std::vector<std::uint8_t>& cand,
                          bool neighbours) {
  auto bits = [](const std::array<std::vector<std::uint32_t>, kToggleContexts>& r, int contexts) {
    std::uint64_t b = 0;
    for (int j = 0; j < contexts; ++j) b += rice_list_bits(r[static_cast<std::size_t>(j)]);
    return b;
  };
  ToggleCoding out;
  if (toggled.empty()) {
    out.bits = bits(out.ranks, kLabelContexts);
    return out;
  }
  const auto ctx = toggle_contexts(dt, inside, &cand, true);
  auto ranks = toggle_ranks(ctx, toggled);
  out.ranks = std::move(ranks[0]);
  out.bits = bits(out.ranks, kLabelContexts);
  const std::uint64_t b = bits(ranks[1], kCandidateContexts);
  if (b < out.bits) out.ranks = std::move(ranks[1]), out.by_candidates = true, out.bits = b;
  const std::uint64_t bv = bits(ranks[2], kToggleContexts);
  if (bv < out.bits) out.ranks = std::move(ranks[2]), out.by_candidates = out.by_vertices = true, out.bits = bv;
  if (!neighbours) return out;
  auto by_neighbours = code_by_neighbours(dt, ctx, toggled);
  if (by_neighbours.bits < out.bits) out = std::move(by_neighbours);
  return out;
}

double bbox_diagonal(const std::vector<GridPoint>& points) {
  double s = 0;
  for (int a = 0; a < 3; ++a) {
    std::uint32_t lo = ~0u, hi = 0;
    for (const auto& p : points) lo = std::min(lo, p[a]), hi = std::max(hi, p[a]);
    s += static_cast<double>(hi - lo) * static_cast<double>(hi - lo);
  }
  return std::sqrt(s);
}

// The length the tolerances are 1/1000 of: the caller's (a tile: the whole
// model's, EncodeOptions::tolerance_diagonal), else the points' own.
double reference_diagonal(const std::vector<GridPoint>& points, const TuneInput& in) {
  return in.diagonal > 0 ? in.diagonal : bbox_diagonal(points);
}

// Smallest height of a tetrahedron (3V over its largest face area): how far
// the surface moves when its label flips.
double height(const std::vector<GridPoint>& points, const std::array<std::uint32_t, 4>& t) {
  Vec3 p[4];
  for (int i = 0; i < 4; ++i) p[i] = {double(points[t[i]][0]), double(points[t[i]][1]), double(points[t[i]][2])};
  auto sub = [](const Vec3& a, const Vec3& b) { return Vec3{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  auto cross = [](const Vec3& a, const Vec3& b) {
    return Vec3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  auto norm = [](const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); };
  const Vec3 n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
  const Vec3 d = sub(p[3], p[0]);
  const double six_v = std::abs(n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
  double max_area2 = 0;  // twice the area
  for (const auto& f : kFaceVertices) max_area2 = std::max(max_area2, norm(cross(sub(p[f[1]], p[f[0]]), sub(p[f[2]], p[f[0]]))));
  return max_area2 > 0 ? six_v / max_area2 : 0;
}

// Vertices on the interface between inside and outside tetrahedra.
std::vector<std::uint8_t> interface_vertices(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside,
                                             std::size_t n) {
  std::vector<std::uint8_t> on(n, 0);
  for (std::size_t t = 0; t < dt.tets.size(); ++t) {
    if (!inside[t]) continue;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u != kNoTet && inside[u]) continue;
      for (int i = 0; i < 3; ++i) on[dt.tets[t][kFaceVertices[k][i]]] = 1;
    }
  }
  return on;
}

// Vertices where the interface of `inside` is unsound: a vertex of `want`
// missing from it, or an endpoint of an edge with other than two faces.
std::vector<std::uint8_t> interface_defects(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside,
                                            const std::vector<std::uint8_t>& want) {
  const std::size_t n = want.size();
  std::vector<std::uint8_t> bad(n, 0);
  const auto have = interface_vertices(dt, inside, n);
  for (std::size_t v = 0; v < n; ++v) bad[v] = want[v] && !have[v];
  // Each interface edge as one key (its vertices, vb bits each), radix
  // sorted: faster than a comparison sort of the horse's 290k edge uses,
  // which tuning sorts on every trial of a coarser level.
  int vb = 1;
  while (vb < 32 && (std::uint64_t{1} << vb) < n) ++vb;
  const std::uint64_t low = (std::uint64_t{1} << vb) - 1;
  std::vector<std::uint64_t> edges;
  for (std::size_t t = 0; t < dt.tets.size(); ++t) {
    if (!inside[t]) continue;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u != kNoTet && inside[u]) continue;
      for (int i = 0; i < 3; ++i) {
        const std::uint64_t a = dt.tets[t][kFaceVertices[k][i]], b = dt.tets[t][kFaceVertices[k][(i + 1) % 3]];
        edges.push_back((std::min(a, b) << vb) | std::max(a, b));
      }
    }
  }
  radix_sort(edges, 2 * vb);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i != 2) bad[edges[i] >> vb] = bad[edges[i] & low] = 1;
    i = j;
  }
  return bad;
}

// Mends the defects (local_defects) that the mismatches of `labels`
// against `truth` leave at the vertices, correcting few of them: at a
// vertex with defects, the mismatched tetrahedron around it whose
// correction removes the most defects at its four vertices (only theirs
// change), while one removes any; where none does, every mismatch around the
// vertex. Corrected tetrahedra are set in `toggled`. Every step corrects a
// mismatch, so it ends.
void mend_defects_locally(const Tetrahedralization& dt, const VertexTets& vt, const std::vector<std::uint8_t>& truth,
                          const std::vector<std::uint8_t>& want, std::vector<std::uint8_t>& labels,
                          std::vector<std::uint8_t>& toggled) {
  const std::size_t n = want.size();
  DefectScratch work;
  auto defects = [&](std::uint32_t v) { return local_defects(dt, labels, vt.start, vt.incident, want, v, work); };
  auto around = [&](std::uint32_t t) {
    int d = 0;
    for (std::uint32_t u : dt.tets[t]) d += defects(u);
    return d;
  };
  std::vector<std::uint32_t> queue;
  std::vector<std::uint8_t> queued(n, 0);
  for (std::uint32_t v = 0; v < n; ++v)
    if (defects(v) > 0) queue.push_back(v), queued[v] = 1;
  auto correct = [&](std::uint32_t t) {
    labels[t] = truth[t];
    toggled[t] = 1;
    for (std::uint32_t u : dt.tets[t])
      if (!queued[u] && defects(u) > 0) queue.push_back(u), queued[u] = 1;
  };
  while (!queue.empty()) {
    const std::uint32_t v = queue.back();
    queue.pop_back();
    queued[v] = 0;
    while (defects(v) > 0) {
      std::uint32_t best = kNoTet;
      int best_gain = 0;
      for (std::uint32_t i = vt.start[v]; i < vt.start[v + 1]; ++i) {
        const std::uint32_t t = vt.incident[i];
        if (labels[t] == truth[t]) continue;
        const int before = around(t);
        labels[t] = truth[t];
        const int gain = before - around(t);
        labels[t] = static_cast<std::uint8_t>(1 - truth[t]);
        if (gain > best_gain) best_gain = gain, best = t;
      }
      if (best != kNoTet) {
        correct(best);
        continue;
      }
      for (std::uint32_t i = vt.start[v]; i < vt.start[v + 1]; ++i)
        if (labels[vt.incident[i]] != truth[vt.incident[i]]) correct(vt.incident[i]);
      break;
    }
  }
}

// The mismatches of `labels` against `truth` that the interface's topology
// hangs on. The mismatched tetrahedra fall into clusters joined through
// shared vertices. Correcting a cluster changes only interface elements
// (vertices, edges, faces) whose vertices all belong to it: an element with
// a vertex outside lies in no tetrahedron of the cluster. So its change of
// the Euler characteristic (vertices - edges + faces) is counted locally,
// and the changes of different clusters add up. Returns the tetrahedra of
// the clusters whose correction changes it, ascending: correcting them all
// gives the truth's Euler characteristic, and leaves every other cluster
// (in practice, flat flips on the surface) to the rule.
std::vector<std::uint32_t> topology_mismatches(const Tetrahedralization& dt, const VertexTets& vt,
                                               const std::vector<std::uint8_t>& labels,
                                               const std::vector<std::uint8_t>& truth) {
  const std::size_t nt = dt.tets.size(), n = vt.start.size() - 1;
  std::vector<std::uint32_t> parent(nt);
  for (std::size_t t = 0; t < nt; ++t) parent[t] = static_cast<std::uint32_t>(t);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t v = 0; v < n; ++v) {
    std::uint32_t first = kNoTet;
    for (std::uint32_t i = vt.start[v]; i < vt.start[v + 1]; ++i) {
      const std::uint32_t t = vt.incident[i];
      if (labels[t] == truth[t]) continue;
      if (first == kNoTet) first = t;
      else parent[find(t)] = find(first);
    }
  }
  std::vector<std::uint64_t> by_cluster;  // (root << 32) | tetrahedron
  for (std::size_t t = 0; t < nt; ++t)
    if (labels[t] != truth[t]) by_cluster.push_back((std::uint64_t{find(static_cast<std::uint32_t>(t))} << 32) | t);
  std::sort(by_cluster.begin(), by_cluster.end());

  std::vector<std::uint8_t> member(nt, 0);
  std::vector<std::uint32_t> stamp(n, ~0u);
  std::vector<std::uint32_t> verts;
  std::vector<std::uint64_t> edges;
  std::vector<std::uint32_t> out;
  // Labels before (after = false) and after correcting the cluster.
  auto label = [&](std::uint32_t t, bool after) -> int {
    if (t == kNoTet) return 0;
    return after && member[t] ? truth[t] : labels[t];
  };
  auto face_on = [&](std::uint32_t t, int k, bool after) { return label(t, after) != label(dt.neighbors[t][k], after); };
  // Whether the interface has a face containing vertex v (vertex_on), or
  // the edge a-b (edge_on).
  auto vertex_on = [&](std::uint32_t v, bool after) {
    for (std::uint32_t i = vt.start[v]; i < vt.start[v + 1]; ++i) {
      const std::uint32_t t = vt.incident[i];
      for (int k = 0; k < 4; ++k)
        if (dt.tets[t][k] != v && face_on(t, k, after)) return true;
    }
    return false;
  };
  auto edge_on = [&](std::uint32_t a, std::uint32_t b, bool after) {
    for (std::uint32_t i = vt.start[a]; i < vt.start[a + 1]; ++i) {
      const std::uint32_t t = vt.incident[i];
      const auto& T = dt.tets[t];
      if (T[0] != b && T[1] != b && T[2] != b && T[3] != b) continue;
      for (int k = 0; k < 4; ++k)
        if (T[k] != a && T[k] != b && face_on(t, k, after)) return true;
    }
    return false;
  };
  for (std::size_t i = 0; i < by_cluster.size();) {
    std::size_t j = i;
    while (j < by_cluster.size() && by_cluster[j] >> 32 == by_cluster[i] >> 32) ++j;
    const auto id = static_cast<std::uint32_t>(i);
    verts.clear();
    edges.clear();
    for (std::size_t m = i; m < j; ++m) member[by_cluster[m] & 0xffffffffu] = 1;
    long change = 0;
    for (std::size_t m = i; m < j; ++m) {
      const auto t = static_cast<std::uint32_t>(by_cluster[m] & 0xffffffffu);
      const auto& T = dt.tets[t];
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t u = dt.neighbors[t][k];
        if (u != kNoTet && member[u] && u < t) continue;  // counted from u
        change += static_cast<long>(face_on(t, k, true)) - static_cast<long>(face_on(t, k, false));
      }
      for (int a = 0; a < 4; ++a) {
        if (stamp[T[a]] != id) stamp[T[a]] = id, verts.push_back(T[a]);
        for (int b = a + 1; b < 4; ++b)
          edges.push_back((std::uint64_t{std::min(T[a], T[b])} << 32) | std::max(T[a], T[b]));
      }
    }
    for (std::uint32_t v : verts) change += static_cast<long>(vertex_on(v, true)) - static_cast<long>(vertex_on(v, false));
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (std::uint64_t e : edges) {
      const auto a = static_cast<std::uint32_t>(e >> 32), b = static_cast<std::uint32_t>(e & 0xffffffffu);
      change -= static_cast<long>(edge_on(a, b, true)) - static_cast<long>(edge_on(a, b, false));
    }
    for (std::size_t m = i; m < j; ++m) {
      const auto t = static_cast<std::uint32_t>(by_cluster[m] & 0xffffffffu);
      member[t] = 0;
      if (change != 0) out.push_back(t);
    }
    i = j;
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Faces of the reconstructed surface (after toggles and the border rule)
// that stray from the input surface: caps across the holes of an open input.
std::vector<std::uint32_t> hole_faces(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                      const ReconParams& p, const std::vector<Vec3>& surface_points,
                                      const std::vector<Triangle>& surface, double diagonal) {
  std::vector<std::uint8_t> cand;
  auto labels = rule_labels(points, dt, local_scale(points, dt, p.scale_rank), p, &cand);
  apply_toggles(dt, p, labels, &cand);
  const SurfaceDistance to_input(surface_points, surface);
  const double tolerance = 1e-3 * diagonal;
  auto on_border = [&](std::uint32_t v) { return std::binary_search(p.border.begin(), p.border.end(), v); };
  std::vector<std::uint32_t> drops;
  for (std::size_t t = 0; t < dt.tets.size(); ++t) {
    if (!labels[t]) continue;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u != kNoTet && labels[u]) continue;
      Vec3 v[3];
      for (int i = 0; i < 3; ++i) {
        const auto& g = points[dt.tets[t][kFaceVertices[k][i]]];
        v[i] = {double(g[0]), double(g[1]), double(g[2])};
      }
      if (on_border(dt.tets[t][kFaceVertices[k][0]]) && on_border(dt.tets[t][kFaceVertices[k][1]]) &&
          on_border(dt.tets[t][kFaceVertices[k][2]]))
        continue;  // the border rule removes it already
      const Vec3 probes[4] = {{(v[0][0] + v[1][0] + v[2][0]) / 3, (v[0][1] + v[1][1] + v[2][1]) / 3, (v[0][2] + v[1][2] + v[2][2]) / 3},
                              {(v[0][0] + v[1][0]) / 2, (v[0][1] + v[1][1]) / 2, (v[0][2] + v[1][2]) / 2},
                              {(v[1][0] + v[2][0]) / 2, (v[1][1] + v[2][1]) / 2, (v[1][2] + v[2][2]) / 2},
                              {(v[0][0] + v[2][0]) / 2, (v[0][1] + v[2][1]) / 2, (v[0][2] + v[2][2]) / 2}};
      for (const auto& q : probes)
        if (to_input(q) > tolerance) {
          drops.push_back(static_cast<std::uint32_t>(4 * t + static_cast<std::size_t>(k)));
          break;
        }
    }
  }
  return drops;
}

// Encoder-side cleanup of a target labelling (levels of octree cells): the input's
// surface carried over to the decoded points can fold where points moved,
// and its winding-number labels then leave pinch points, non-manifold
// edges or points off the surface. A greedy local search flips tetrahedra
// around such vertices while that strictly lowers the defects of the
// vertices involved (defects as in spec 11.4a, here without its Euler
// constraint: the aim is the input's topology, not the folded target's).
// Returns the number of flips.
class TargetCleaner {
 public:
  // `flippable`: the tetrahedra the search may flip (empty: all).
  TargetCleaner(const Tetrahedralization& dt, const std::vector<std::uint8_t>& want,
                const std::vector<std::uint8_t>& flippable = {})
      : dt_(dt), want_(want), flippable_(flippable) {
    auto around = vertex_tets(dt, want.size());
    start_ = std::move(around.start);
    incident_ = std::move(around.incident);
  }

  std::size_t run(std::vector<std::uint8_t>& inside, int rounds) {
    const std::size_t n = want_.size();
    std::vector<int> cache(n, -1);
    auto defects = [&](std::uint32_t v) {
      if (cache[v] < 0) cache[v] = local(inside, v);
      return cache[v];
    };
    auto around = [&](std::uint32_t t) {
      int d = 0;
      for (auto v : dt_.tets[t]) d += defects(v);
      return d;
    };
    auto flip = [&](std::uint32_t t) {
      inside[t] ^= 1;
      for (auto v : dt_.tets[t]) cache[v] = -1;
    };
    std::size_t flips = 0;
    for (int round = 0; round < rounds; ++round) {
      bool changed = false;
      for (std::uint32_t v = 0; v < n; ++v) {
        if (defects(v) == 0) continue;
        for (std::uint32_t i = start_[v]; i < start_[v + 1]; ++i) {
          const std::uint32_t t = incident_[i];
          if (!flippable_.empty() && !flippable_[t]) continue;
          const int before = around(t);
          const auto& tv = dt_.tets[t];
          const int was[4] = {cache[tv[0]], cache[tv[1]], cache[tv[2]], cache[tv[3]]};
          flip(t);
          // Defects are never negative: stop adding once the sum reaches
          // the old one.
          int after = 0;
          for (int k = 0; k < 4 && after < before; ++k) after += defects(tv[k]);
          if (after < before) {
            changed = true;
            ++flips;
            if (defects(v) == 0) break;
          } else {
            inside[t] ^= 1;  // back: the cached defects are the old ones again
            for (int k = 0; k < 4; ++k) cache[tv[k]] = was[k];
          }
        }
      }
      if (!changed) break;
    }
    return flips;
  }

 private:
  int local(const std::vector<std::uint8_t>& inside, std::uint32_t v) {
    return local_defects(dt_, inside, start_, incident_, want_, v, work_);
  }

  const Tetrahedralization& dt_;
  const std::vector<std::uint8_t>& want_;
  const std::vector<std::uint8_t>& flippable_;
  std::vector<std::uint32_t> start_, incident_;
  DefectScratch work_;
};

// What a repaired coarser level still gets wrong: unsound vertices, and a
// topology other than the input's (weighted far above any defect).
std::uint64_t approximation_penalty(const Tetrahedralization& dt, const std::vector<std::uint8_t>& labels,
                                    const std::vector<std::uint8_t>& want, const TuneInput& in) {
  std::uint64_t m = 0;
  for (auto d : interface_defects(dt, labels, want)) m += d;
  if (in.target_components) {
    const auto [comps, euler] = interface_topology(dt, labels);
    m += 100 * static_cast<std::uint64_t>(std::labs(euler - in.target_euler));
    m += 100 * static_cast<std::uint64_t>(comps > in.target_components ? comps - in.target_components
                                                                        : in.target_components - comps);
  }
  return m;
}

}  // namespace

// Components (of faces joined by edges) and Euler characteristic of a
// triangle list. The edges are sorted as one 64-bit key each (the edge's
// vertices and the face's index) by radix sort where their bits fit, not as
// pairs by comparison (the horse's interface has 97k faces, and the tuning
// of every level counts it a few times: its 4-level encode takes 4 % less).
std::pair<std::size_t, long> surface_topology(const std::vector<Triangle>& faces) {
  std::uint32_t top = 0;
  for (const auto& f : faces) top = std::max({top, f[0], f[1], f[2]});
  long nv = 0;
  if (std::uint64_t{top} < 8 * std::uint64_t{faces.size()}) {  // a flag per vertex index
    std::vector<std::uint8_t> used(faces.empty() ? 0 : std::size_t{top} + 1, 0);
    for (const auto& f : faces)
      for (std::uint32_t v : f)
        if (!used[v]) used[v] = 1, ++nv;
  } else {  // sparse indices
    std::vector<std::uint32_t> verts;
    verts.reserve(3 * faces.size());
    for (const auto& f : faces) verts.insert(verts.end(), f.begin(), f.end());
    std::sort(verts.begin(), verts.end());
    nv = static_cast<long>(std::unique(verts.begin(), verts.end()) - verts.begin());
  }
  std::vector<std::uint32_t> parent(faces.size());
  for (std::uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto bits_of = [](std::uint64_t x) {
    int b = 0;
    while (x >> b) ++b;
    return b;
  };
  const int vb = bits_of(top), fb = bits_of(faces.size());
  long ne = 0;
  // Joins the faces of each run of equal edges (same(i, j): entries i and j
  // are one edge; face(i): entry i's face), counting the edges.
  auto join = [&](std::size_t count, auto same, auto face) {
    for (std::size_t i = 0; i < count;) {
      std::size_t j = i;
      while (j < count && same(i, j)) {
        parent[find(face(j))] = find(face(i));
        ++j;
      }
      ++ne;
      i = j;
    }
  };
  if (2 * vb + fb <= 64) {
    std::vector<std::uint64_t> keys;
    keys.reserve(3 * faces.size());
    for (std::uint32_t i = 0; i < faces.size(); ++i)
      for (int a = 0; a < 3; ++a) {
        const std::uint64_t x = faces[i][a], y = faces[i][(a + 1) % 3];
        keys.push_back(((std::min(x, y) << vb | std::max(x, y)) << fb) | i);
      }
    radix_sort(keys, 2 * vb + fb);
    const std::uint64_t face_mask = fb == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << fb) - 1;
    join(
        keys.size(), [&](std::size_t i, std::size_t j) { return (keys[i] >> fb) == (keys[j] >> fb); },
        [&](std::size_t i) { return static_cast<std::uint32_t>(keys[i] & face_mask); });
  } else {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;
    edges.reserve(3 * faces.size());
    for (std::uint32_t i = 0; i < faces.size(); ++i)
      for (int a = 0; a < 3; ++a) {
        const std::uint64_t x = faces[i][a], y = faces[i][(a + 1) % 3];
        edges.push_back({(std::min(x, y) << 32) | std::max(x, y), i});
      }
    std::sort(edges.begin(), edges.end());
    join(
        edges.size(), [&](std::size_t i, std::size_t j) { return edges[i].first == edges[j].first; },
        [&](std::size_t i) { return edges[i].second; });
  }
  std::size_t comps = 0;
  for (std::uint32_t i = 0; i < parent.size(); ++i) comps += find(i) == i;
  return {comps, nv - ne + static_cast<long>(faces.size())};
}

// Components (of faces joined by edges) and Euler characteristic of the
// interface between inside and outside tetrahedra.
std::pair<std::size_t, long> interface_topology(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside) {
  std::vector<Triangle> faces;
  for (std::size_t t = 0; t < dt.tets.size(); ++t) {
    if (!inside[t]) continue;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u != kNoTet && inside[u]) continue;
      faces.push_back({dt.tets[t][kFaceVertices[k][0]], dt.tets[t][kFaceVertices[k][1]], dt.tets[t][kFaceVertices[k][2]]});
    }
  }
  return surface_topology(faces);
}

std::vector<std::uint8_t> truth_labels(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                       const std::vector<Vec3>& surface_points, const std::vector<Triangle>& surface,
                                       const std::vector<Triangle>& input_faces_on_points, WindingCache* cache,
                                       bool sheet, double* unsure, const std::array<std::uint32_t, 6>* seal_box) {
  const std::size_t nt = dt.tets.size();
  // The structures of an earlier call on the same surface (the input's,
  // level after level) are the same structures.
  const bool same = cache && cache->points == &surface_points && cache->surface == &surface;
  std::shared_ptr<const ClosedSurface> closed = same ? cache->closed : nullptr;
  std::shared_ptr<const WindingNumber> tree = same ? cache->tree : nullptr, caps = same ? cache->caps : nullptr;
  if (!closed && ClosedSurface::exact(surface_points)) {
    closed = std::make_shared<const ClosedSurface>(surface_points, surface, seal_box);
    // The caps of cuts around a seal box stay: the surface closed by them.
    std::vector<Triangle> subtracted;
    for (std::size_t c = 0; c < closed->caps().size(); ++c)
      if (!closed->cap_outside()[c]) subtracted.push_back(closed->caps()[c]);
    if (!subtracted.empty()) caps = std::make_shared<const WindingNumber>(closed->cap_points(), subtracted);
  }
  // The winding number of the surface summed over its triangles: where the
  // closed surface's cannot be counted exactly, and for points off the grid.
  auto direct = [&](const Vec3& c) {
    if (!tree) tree = std::make_shared<const WindingNumber>(surface_points, surface);
    return (*tree)(c);
  };
  std::vector<double> w(nt);
  auto centroid = [&](std::size_t t) {
    Vec3 c{0, 0, 0};
    for (auto v : dt.tets[t])
      for (int a = 0; a < 3; ++a) c[a] += 0.25 * points[v][a];
    return c;
  };
  if (closed) {
    // The closed surface's winding number W, an integer off it, counted
    // from one centroid to the next in the Morton order of the centroids
    // (short segments, which open the same boxes one after the other), and
    // where a count is degenerate, from a neighbour's centroid or from a
    // point outside; a tetrahedron that no count reaches (its centroid on
    // a triangle) gets the plain sum. Centroids in quarter units: four
    // times, integers.
    std::vector<ClosedSurface::Point> c4(nt);
    std::int64_t any4 = 0;
    for (std::size_t t = 0; t < nt; ++t) {
      ClosedSurface::Point c{0, 0, 0};
      for (auto v : dt.tets[t])
        for (int a = 0; a < 3; ++a) c[a] += points[v][a];
      c4[t] = c;
      any4 |= c[0] | c[1] | c[2];
    }
    int shift = 0;  // 12 bits per axis of the Morton key, 28 of the index
    while ((any4 >> shift) >= (std::int64_t{1} << 12)) ++shift;
    constexpr int kIndexBits = 28;
    const bool reorder = nt < (std::size_t{1} << kIndexBits);
    std::vector<std::uint64_t> order(nt);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto& c = c4[t];
      const GridPoint m{static_cast<std::uint32_t>(c[0] >> shift), static_cast<std::uint32_t>(c[1] >> shift),
                        static_cast<std::uint32_t>(c[2] >> shift)};
      order[t] = reorder ? morton_key(m, 12) << kIndexBits | t : t;
    }
    if (reorder) radix_sort(order, 64);
    const std::uint64_t index_mask = reorder ? (std::uint64_t{1} << kIndexBits) - 1 : ~std::uint64_t{0};
    std::vector<int> winding(nt);
    std::vector<std::uint8_t> state(nt, 0);  // 0 unknown, 1 counted, 2 summed
    std::vector<std::uint32_t> summed;
    std::size_t last = nt;  // the last counted tetrahedron
    for (const std::uint64_t key : order) {
      const auto t = static_cast<std::size_t>(key & index_mask);
      std::optional<int> w_t;
      if (last < nt)
        if (const auto j = closed->jump(c4[last], c4[t])) w_t = winding[last] + *j;
      for (int k = 0; k < 4 && !w_t; ++k) {
        const std::uint32_t u = dt.neighbors[t][k];
        if (u != kNoTet && state[u] == 1)
          if (const auto j = closed->jump(c4[u], c4[t])) w_t = winding[u] + *j;
      }
      for (int which = 0; which < 4 && !w_t; ++which) w_t = closed->jump(closed->outside(which), c4[t]);
      if (!w_t) {
        state[t] = 2;
        summed.push_back(static_cast<std::uint32_t>(t));
        continue;
      }
      state[t] = 1;
      winding[t] = *w_t;
      last = t;
    }
    // Building the tree (the horse's: about 0.1 s, 3 % of its encode) costs
    // more than a few plain sums over the surface's triangles, and few
    // centroids need either (the horse: 2 of 329,502).
    constexpr std::size_t kPlainSums = 32;
    for (std::uint32_t t : summed)
      w[t] = tree || summed.size() > kPlainSums ? direct(centroid(t)) : winding_number(surface_points, surface, centroid(t));
    // The surface's own: W less the caps' (an open surface's).
    split_range(cache ? cache->helpers : nullptr, nt, 1024, [&](std::size_t from, std::size_t to) {
      for (std::size_t t = from; t < to; ++t)
        if (state[t] == 1) w[t] = winding[t] - (caps ? (*caps)(centroid(t)) : 0.0);
    });
  } else {
    for (std::size_t t = 0; t < nt; ++t) w[t] = direct(centroid(t));
  }
  if (!sheet)
    for (auto& v : w) v = std::abs(v);
  if (cache) {
    cache->points = &surface_points;
    cache->surface = &surface;
    cache->closed = closed;
    cache->tree = tree;
    cache->caps = caps;
  }
  std::vector<std::uint8_t> label(nt);
  std::vector<std::uint8_t> sure(nt);
  if (sheet) {
    double sum = 0;  // the prevailing orientation: the sign of the clear values' sum
    for (std::size_t t = 0; t < nt; ++t)
      if (std::abs(w[t]) > 0.25) sum += w[t];
    const double sign = sum < 0 ? -1.0 : 1.0;
    for (std::size_t t = 0; t < nt; ++t) {
      const double v = sign * w[t];
      label[t] = v > 0.1;
      sure[t] = std::abs(v - 0.1) > 0.2;
    }
  } else {
    for (std::size_t t = 0; t < nt; ++t) {
      label[t] = w[t] > 0.5;
      sure[t] = w[t] < 0.25 || w[t] > 0.75;
    }
  }
  if (unsure) {
    const auto open = static_cast<double>(std::count(sure.begin(), sure.end(), std::uint8_t{0}));
    *unsure = nt ? open / static_cast<double>(nt) : 0.0;
  }
  // A tetrahedron whose centroid lies near the surface (flat ones on it):
  // across an input face the label changes, across any other face it does
  // not. Settle it by the votes of settled neighbours, a few rounds.
  std::vector<Face> faces;
  faces.reserve(input_faces_on_points.size());
  for (const auto& f : input_faces_on_points) faces.push_back(sorted(f));
  std::sort(faces.begin(), faces.end());
  auto is_input = [&](const Face& f) { return std::binary_search(faces.begin(), faces.end(), sorted(f)); };
  for (int round = 0; round < 8; ++round) {
    bool changed = false;
    for (std::size_t t = 0; t < nt; ++t) {
      if (sure[t]) continue;
      int in = 0, out = 0;
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t u = dt.neighbors[t][k];
        const Face f{dt.tets[t][kFaceVertices[k][0]], dt.tets[t][kFaceVertices[k][1]], dt.tets[t][kFaceVertices[k][2]]};
        const bool cut = is_input(f);
        if (u == kNoTet) {
          (cut ? in : out) += 1;  // beyond the hull is outside
        } else if (sure[u]) {
          ((label[u] != 0) != cut ? in : out) += 1;
        }
      }
      if (in != out && (in > 0 || out > 0)) {
        label[t] = in > out;
        sure[t] = 1;
        changed = true;
      }
    }
    if (!changed) break;
  }
  return label;
}

ReconParams tune(const std::vector<GridPoint>& points, const Tetrahedralization& dt, Kind kind, const TuneInput& in,
                 Fidelity fidelity, TuningReport* report) {
  const auto& in_truth = in.truth;
  const auto& border = in.border;
  const std::size_t n = points.size(), nt = dt.tets.size();
  ReconParams best;
  best.border = border;
  best.seal = in.seal;
  best.seal_box = in.seal_box;
  if (nt == 0 || kind == Kind::points || in_truth.empty()) return best;

  // With a seal box (a tile's stream, spec 11.3, tiles.md §5), the merged
  // model keeps only the simplices whose first vertex lies in the box: a
  // tetrahedron with no vertex in it never shows, so its label is left to
  // the rule, and only faces with a vertex in the box need to be
  // candidates. (A 31,412-point tile of a 60,000-point torus, q = 14,
  // fidelity exact: without a seal, 60,035 mismatches to correct and 10,012
  // bytes of RCON; with it, 11,839 and 3,542, against 5,940 bytes for the
  // whole torus.)
  auto in_box = [&](std::uint32_t v) { return in_seal_box(points[v], in.seal_box); };
  std::vector<std::uint8_t> care;
  if (in.seal) {
    care.resize(nt);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto& T = dt.tets[t];
      care[t] = in_box(T[0]) || in_box(T[1]) || in_box(T[2]) || in_box(T[3]);
    }
  }

  // need[v]: the longest edge of the true interface (surface) or of the true
  // boundary faces (volume) at v; every such face must stay a candidate.
  std::vector<std::uint64_t> need(n, 0);
  for (std::size_t t = 0; t < nt; ++t) {
    if (!in_truth[t]) continue;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t u = dt.neighbors[t][k];
      if (u != kNoTet && in_truth[u]) continue;
      const auto& tet = dt.tets[t];
      if (in.seal && !in_box(tet[kFaceVertices[k][0]]) && !in_box(tet[kFaceVertices[k][1]]) &&
          !in_box(tet[kFaceVertices[k][2]]))
        continue;  // sealed: the flood does not cross it, candidate or not
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t a = tet[kFaceVertices[k][i]], b = tet[kFaceVertices[k][(i + 1) % 3]];
        const std::uint64_t d = dist2(points[a], points[b]);
        need[a] = std::max(need[a], d);
        need[b] = std::max(need[b], d);
      }
    }
  }

  const std::vector<std::uint8_t> want_all(n, kind == Kind::surface ? 1 : 0);
  // The edge test's lengths, shared by every trial below (and their helper).
  const TetEdgeLengths edges(points, dt, in.helpers);
  // The peeling's decisions, shared the same way (filled as trials need them).
  PeelMemo peels(nt);
  // What parameters p leave to correct: the rule's labels that differ from
  // the truth or, on a coarser level that relies on the decoder's repair,
  // what the repair cannot mend.
  // labels: the rule's (after the repair, when p sets it), kept for the
  // parameters tuning chooses.
  // Returns that count and its price in bits: what the toggle lists of the
  // mismatches cost (fidelity shape leaves the thin ones to the rule, so a
  // bound) or, where no toggles mend them (fidelity rule, the repair's
  // leftovers), a list of indices over all tetrahedra, dearer per entry:
  // the rule's own errors stay in the output, and cheap toggle contexts must
  // not make them cheap (priced as toggles, rule-fidelity streams of the
  // Stanford bunny reproduced 67 % of its triangles instead of 91 %).
  // Pricing the thin mismatches of fidelity shape that way too was measured
  // and dropped: more classes, more side bits than fidelity exact (bunny
  // 1.53 against 1.10 bits per point) for 93 % of fertility's triangles
  // instead of 90 %, where exact gives 99.9 %.
  // `memo` (FilterMemo): only for calls made one at a time (the trials
  // evaluated on two threads have no filters).
  auto cost = [&](const ReconParams& p, const std::vector<std::uint64_t>& scale, std::vector<std::uint8_t>& labels,
                  FilterMemo* memo = nullptr) {
    std::vector<std::uint8_t> cand;
    labels = rule_labels(points, dt, scale, p, &cand, nullptr, memo, &edges, &peels);
    if (p.repair) {
      repair_labels(dt, kind, labels);
      const std::uint64_t m = approximation_penalty(dt, labels, want_all, in);
      return std::pair<std::uint64_t, std::uint64_t>{m, list_bits(m, nt)};
    }
    std::vector<std::uint32_t> wrong;
    for (std::size_t t = 0; t < nt; ++t)
      if (labels[t] != in_truth[t] && (care.empty() || care[t])) wrong.push_back(static_cast<std::uint32_t>(t));
    const std::uint64_t m = wrong.size();
    if (fidelity == Fidelity::rule) return std::pair<std::uint64_t, std::uint64_t>{m, list_bits(m, nt)};
    return std::pair<std::uint64_t, std::uint64_t>{m, code_toggles(dt, labels, wrong, cand, false).bits};
  };
  std::uint64_t best_bits = ~std::uint64_t{0};
  std::uint64_t best_mismatch = 0, best_correction_bits = 0;
  std::vector<std::uint8_t> trial, best_labels;
  // A surface vertex has about six surface neighbours; a volume's boundary
  // vertex more Delaunay edges inside the solid.
  const std::vector<std::uint32_t> ranks = kind == Kind::surface ? std::vector<std::uint32_t>{6}
                                                                  : std::vector<std::uint32_t>{6, 10};
  std::vector<std::uint64_t> best_scale;  // local_scale() at best.scale_rank
  // The parameters of every trial so far (scale rank, peel, repair, class
  // limits: all a trial's cost depends on besides the level itself).
  std::set<std::vector<std::uint32_t>> tried;
  for (std::uint32_t rank : ranks) {
    auto scale = local_scale(points, dt, rank);
    // Multiplier each vertex needs, in 1/256 units, capped to the table range.
    std::vector<std::uint32_t> ratio(n, 1);
    for (std::size_t v = 0; v < n; ++v) {
      if (need[v] == 0 || scale[v] == 0) continue;
      const std::uint64_t r = (256 * need[v] + scale[v] - 1) / scale[v];
      ratio[v] = static_cast<std::uint32_t>(std::min<std::uint64_t>(std::max<std::uint64_t>(r, 1), 65535));
    }
    std::vector<std::uint32_t> sorted_ratio(ratio);
    std::sort(sorted_ratio.begin(), sorted_ratio.end());
    // Class limits at the needed ratios of the vertices at the given ranks
    // (ascending; the last class covers every vertex), each vertex in the
    // smallest class that admits its edges.
    auto with_classes = [&](const std::vector<std::size_t>& splits, ReconParams& p) {
      p.scale_rank = rank;
      p.border = border;
      p.seal = in.seal;
      p.seal_box = in.seal_box;
      p.multipliers.clear();
      p.vertex_class.clear();
      for (std::size_t q : splits)
        if (p.multipliers.empty() || sorted_ratio[q] > p.multipliers.back()) p.multipliers.push_back(sorted_ratio[q]);
      if (p.multipliers.empty() || sorted_ratio.back() > p.multipliers.back()) p.multipliers.push_back(sorted_ratio.back());
      p.multipliers.front() = std::max<std::uint32_t>(p.multipliers.front(), 1);
      if (p.multipliers.size() == 1) return std::uint64_t{0};
      p.vertex_class.resize(n);
      std::vector<std::uint64_t> freq(p.multipliers.size(), 0);
      for (std::size_t v = 0; v < n; ++v) {
        const auto it = std::lower_bound(p.multipliers.begin(), p.multipliers.end(), ratio[v]);
        p.vertex_class[v] = static_cast<std::uint8_t>(it - p.multipliers.begin());
        ++freq[p.vertex_class[v]];
      }
      // The classes travel in groups (spec section 10), at about their entropy.
      double bits = 0;
      for (auto f : freq)
        if (f) bits -= static_cast<double>(f) * std::log2(static_cast<double>(f) / static_cast<double>(n));
      return static_cast<std::uint64_t>(bits) + 8 * p.multipliers.size();
    };
    // Trials (parameters, their class bits), decided in order: each is kept
    // when it costs fewer bits than the best so far. No mismatch is the
    // least a trial can reach: when even that does not beat the best, it is
    // not evaluated (the same choice, sooner; volumes' coarser levels often
    // reach it with the first trial). The trials do not depend on each
    // other: with a helper thread free, it evaluates the second half (against
    // the best at the start, which only falls) while this thread evaluates
    // and decides the first; the second half is decided after it, in order,
    // on the same costs, so the choice is the one-thread choice. Returns the
    // index of the last trial kept, or -1.
    struct Trial {
      Trial(const ReconParams& params, std::uint64_t bits) : p(params), class_bits(bits) {}
      ReconParams p;
      std::uint64_t class_bits = 0;
      bool repeated = false;  // the parameters of an earlier trial
      bool evaluated = false;
      std::uint64_t mismatches = 0, correction_bits = 0;
      std::vector<std::uint8_t> labels;
    };
    auto consider = [&](std::vector<Trial>& trials) {
      // A trial with the parameters of an earlier one (moves that undo the
      // last step, class limits that merge) costs what that one cost, which
      // did not beat the best then, or became it and has been beaten since:
      // it cannot be kept, and is not evaluated again.
      for (Trial& t : trials) {
        std::vector<std::uint32_t> key{rank, t.p.peel ? 1u : 0u, t.p.repair ? 1u : 0u};
        key.insert(key.end(), t.p.multipliers.begin(), t.p.multipliers.end());
        t.repeated = !tried.insert(std::move(key)).second;
      }
      auto evaluate = [&](Trial& t, std::uint64_t bound) {
        if (t.repeated || t.class_bits + list_bits(0, nt) >= bound) return;
        std::tie(t.mismatches, t.correction_bits) = cost(t.p, scale, t.labels);
        t.evaluated = true;
      };
      long kept = -1;
      auto decide = [&](std::size_t i) {
        Trial& t = trials[i];
        if (!t.evaluated || t.class_bits + list_bits(0, nt) >= best_bits) return;
        const std::uint64_t bits = t.class_bits + t.correction_bits;
        if (bits >= best_bits) return;
        best_bits = bits;
        best_mismatch = t.mismatches;
        best_correction_bits = t.correction_bits;
        best = t.p;
        best_labels.swap(t.labels);
        kept = static_cast<long>(i);
      };
      const std::size_t m = trials.size(), half = m / 2;
      std::future<void> other;
      if (in.helpers && m > 1)
        other = in.helpers->try_run([&trials, &evaluate, half, m, start = best_bits] {
          for (std::size_t i = half; i < m; ++i) evaluate(trials[i], start);
        });
      const std::size_t mine = other.valid() ? half : m;
      for (std::size_t i = 0; i < mine; ++i) {
        evaluate(trials[i], best_bits);
        decide(i);
      }
      if (other.valid()) other.get();
      for (std::size_t i = mine; i < m; ++i) decide(i);
      return kept;
    };
    // Equal shares first: 1, 2, 4, 8 or 16 classes.
    std::vector<std::size_t> best_splits;
    for (int classes : {1, 2, 4, 8, 16}) {
      // Each trial on a coarser level runs the repair (unless the fidelity
      // is rule), which mends what one class leaves: when 2 and 4 classes
      // were tried there too, all 39 coarser levels of the shared models
      // (4 levels) kept one.
      const bool repairs = in.approximate && fidelity != Fidelity::rule;
      if ((repairs && classes > 1) || (in.approximate && classes > 4)) break;
      std::vector<std::size_t> splits;
      for (int c = 1; c < classes; ++c) splits.push_back(std::min(n - 1, (n * static_cast<std::size_t>(c)) / static_cast<std::size_t>(classes)));
      ReconParams p;
      const std::uint64_t class_bits = with_classes(splits, p);
      std::vector<Trial> trials;
      for (bool peel : {false, true}) {
        p.peel = peel;
        p.repair = repairs;
        trials.emplace_back(p, class_bits);
      }
      if (consider(trials) >= 0) best_splits = splits;
    }
    // Then unequal shares: classes cost n·H(shares) bits, so a large class of
    // small limits and a few small classes of large ones is often cheaper at
    // about the same mismatches. Greedily add, drop or move one limit among
    // fixed quantiles while the estimate falls.
    if (!in.approximate && n >= 64 && best.scale_rank == rank) {
      static constexpr int kPermille[] = {300, 500, 650, 750, 850, 900, 950, 980, 995};
      std::vector<std::size_t> grid;
      for (int pm : kPermille) grid.push_back(std::min(n - 1, n * static_cast<std::size_t>(pm) / 1000));
      const bool peel = best.peel;
      for (int step = 0; step < 6; ++step) {
        std::vector<std::vector<std::size_t>> moves;
        for (std::size_t g : grid)
          if (std::find(best_splits.begin(), best_splits.end(), g) == best_splits.end() && best_splits.size() < 4) {
            auto s2 = best_splits;
            s2.insert(std::upper_bound(s2.begin(), s2.end(), g), g);
            moves.push_back(s2);
          }
        for (std::size_t i = 0; i < best_splits.size(); ++i) {
          auto s2 = best_splits;
          s2.erase(s2.begin() + static_cast<std::ptrdiff_t>(i));
          moves.push_back(s2);
        }
        std::vector<Trial> trials;
        for (const auto& s2 : moves) {
          ReconParams p;
          const std::uint64_t class_bits = with_classes(s2, p);
          p.peel = peel;
          trials.emplace_back(p, class_bits);
        }
        const long kept = consider(trials);
        if (kept < 0) break;
        best_splits = moves[static_cast<std::size_t>(kept)];
      }
    }
    if (best.scale_rank == rank) best_scale = std::move(scale);
  }
  // The thesis' filters (§2.3.2): keep each one that makes the corrections
  // of what the rule gets wrong cheaper (coarser levels repair instead).
  // The trials of the neighbour filters (and the candidates of the chosen
  // parameters, below) share those filters' face data.
  FilterMemo memo;
  {
    const auto& scale = best_scale;
    std::uint64_t current = best_mismatch, current_bits = best_correction_bits;  // cost(best, scale), known
    const std::pair<int, std::uint32_t> tries[] = {{kCircleRadius, 512}, {kEdgeRatio, 16},       {kDensity, 1024},
                                                   {kLone, 1},           {kNeighbourRadius, 4096}, {kNeighbourRatio, 32}};
    for (const auto& [id, threshold] : tries) {
      if (in.approximate) break;  // coarser levels: the repair does better, at no cost
      if (current == 0) break;    // nothing left for a filter to mend
      ReconParams p = best;
      p.filters[static_cast<std::size_t>(id)] = threshold;
      const auto [c, c_bits] = cost(p, scale, trial, &memo);
      if (c_bits < current_bits) {
        current = c;
        current_bits = c_bits;
        best = p;
        best_labels.swap(trial);
      }
    }
    best_mismatch = current;
  }
  // What the corrections aim at: the truth, except where no tile keeps a
  // simplex (with a seal), where the rule's own labels stand.
  std::vector<std::uint8_t> own_truth;
  if (!care.empty()) {
    own_truth = in_truth;
    for (std::size_t t = 0; t < nt; ++t)
      if (!care[t]) own_truth[t] = best_labels[t];
  }
  const std::vector<std::uint8_t>& truth = care.empty() ? in_truth : own_truth;
  if (best.repair) {
    // The decoder repairs the rule's labels itself: nothing to correct.
  } else if (fidelity != Fidelity::rule) {
    const double tolerance = fidelity == Fidelity::exact ? -1.0
                             : in.shape_tolerance >= 0 ? in.shape_tolerance
                                                       : 1e-3 * reference_diagonal(points, in);
    const auto& rule = best_labels;  // rule_labels() for best, without the repair
    auto labels = rule;
    std::vector<std::uint8_t> toggled(nt, 0);
    for (std::size_t t = 0; t < nt; ++t)
      if (labels[t] != truth[t] && height(points, dt.tets[t]) > tolerance) toggled[t] = 1, labels[t] = truth[t];
    // Flat flips are left to the rule only while the result stays as sound as
    // the input's: every vertex the input puts on the surface stays on it and
    // no edge becomes non-manifold. Correct the mismatches around any defect
    // until none is left.
    const auto want = interface_vertices(dt, truth, n);
    auto mend_defects = [&] {
      for (int round = 0; round < 8; ++round) {
        const auto defects = interface_defects(dt, labels, want);
        bool any = false;
        for (std::size_t t = 0; t < nt; ++t) {
          if (labels[t] == truth[t]) continue;
          for (auto v : dt.tets[t])
            if (defects[v]) {
              toggled[t] = 1;
              labels[t] = truth[t];
              any = true;
              break;
            }
        }
        if (!any) break;
      }
    };
    // Fidelity topology mends the defects with fewer corrections
    // (mend_defects_locally) first.
    const bool topology_only = fidelity == Fidelity::topology;
    const VertexTets by_vertex = topology_only ? vertex_tets(dt, n) : VertexTets{};
    if (topology_only) mend_defects_locally(dt, by_vertex, truth, want, labels, toggled);
    mend_defects();
    // Thin flips must not change the topology either: if the surface's
    // components or Euler characteristic differ from the input's, fidelity
    // topology corrects the clusters of mismatches whose correction changes
    // the Euler characteristic (topology_mismatches) and mends the defects
    // that leaves; if the topology still differs (and always with fidelity
    // shape), every mismatch is corrected. Shape's fallback makes it nearly
    // exact on the horse, skull, rocker_arm and Stanford bunny (1 level: 99.4
    // to 99.97 % of the input's triangles that can be kept); topology keeps
    // 67 to 89 % of them, at the same components and Euler characteristic
    // (the open bunny's aside), with 43 to 73 % of the side information
    // (bench/results/fidelity.md).
    const auto target = interface_topology(dt, truth);
    if (interface_topology(dt, labels) != target) {
      if (topology_only) {
        for (std::uint32_t t : topology_mismatches(dt, by_vertex, labels, truth)) toggled[t] = 1, labels[t] = truth[t];
        mend_defects_locally(dt, by_vertex, truth, want, labels, toggled);
        mend_defects();
      }
      if (interface_topology(dt, labels) != target)
        for (std::size_t t = 0; t < nt; ++t)
          if (labels[t] != truth[t]) toggled[t] = 1, labels[t] = truth[t];
    }
    if (in.clean_target) {
      // The target itself may be unsound: a cell level's carried surface
      // folds, and where input triangles are not Delaunay the winding-number
      // labels can pinch or leave non-manifold edges. Mend it, and keep the
      // result if it is sounder, counting a topology other than the input's
      // far above any defect.
      const std::vector<std::uint8_t> want_clean(n, kind == Kind::surface ? 1 : 0);
      const std::uint64_t before = approximation_penalty(dt, labels, want_clean, in);
      if (before > 0) {
        // Only tetrahedra whose edges are at most about 1.4 times the longest
        // target edge at their vertices: mending a fold or a pinch must not
        // grow a bump (on the horse, allowing twice that length moves the
        // surface by 0.6% of the diagonal instead of 0.25%).
        std::vector<std::uint8_t> small(nt, 0);
        for (std::size_t t = 0; t < nt; ++t) {
          const auto& T = dt.tets[t];
          std::uint64_t longest = 0, reach = 0;
          for (int i = 0; i < 4; ++i) {
            reach = std::max(reach, need[T[i]]);
            for (int j = i + 1; j < 4; ++j) longest = std::max(longest, dist2(points[T[i]], points[T[j]]));
          }
          small[t] = longest <= 2 * reach;
        }
        auto cleaned = labels;
        TargetCleaner(dt, want_clean, small).run(cleaned, 8);
        repair_labels(dt, kind, cleaned);
        if (approximation_penalty(dt, cleaned, want_clean, in) < before) labels.swap(cleaned);
      }
      for (std::size_t t = 0; t < nt; ++t) toggled[t] = labels[t] != rule[t];
    } else if (kind == Kind::surface && fidelity != Fidelity::exact && !in.approximate) {
      // An open input surface: with no topology to aim at, mending the
      // target as above opens more holes than it closes. Its edges with more
      // than two faces (where input triangles are not Delaunay, the winding
      // numbers' labels pinch) are still mended, by the repair's local
      // search with no point required on the surface, so that only edge
      // defects count and every flip keeps the Euler characteristic; kept
      // when fewer are left. The Stanford bunny: 9 non-manifold edges
      // -> 1, 265 border edges -> 266, side information 1.102 -> 1.100 bits
      // per point.
      const std::vector<std::uint8_t> edges_only(n, 0);
      const std::uint64_t before = approximation_penalty(dt, labels, edges_only, in);
      if (before > 0) {
        auto mended = labels;
        repair_search(dt, mended, edges_only);
        if (approximation_penalty(dt, mended, edges_only, in) < before) labels.swap(mended);
      }
      for (std::size_t t = 0; t < nt; ++t) toggled[t] = labels[t] != rule[t];
    }
    std::vector<std::uint32_t> list;
    for (std::size_t t = 0; t < nt; ++t)
      if (toggled[t]) list.push_back(static_cast<std::uint32_t>(t));
    // Spec 11.5, candidate contexts: where the rule errs also depends on how
    // many of a tetrahedron's faces are candidates (on the 1-level streams of
    // the shared models, the toggles of the skull, horse and bunny cost 29 to
    // 42 % less).
    auto cand = candidate_flags(points, dt, best_scale, best, nullptr, &memo, &edges);
    if (report) report->corrections = list.size();
    auto coding = code_toggles(dt, rule, list, cand, true);
    if (coding.by_neighbours) {
      best.toggle_ranks = {};
      best.neighbour_lists = std::move(coding.lists);
      best.neighbour_inverted = std::move(coding.inverted);
    } else {
      best.toggle_ranks = std::move(coding.ranks);
    }
    best.candidate_contexts = coding.by_candidates;
    best.vertex_contexts = coding.by_vertices;
    best.neighbour_contexts = coding.by_neighbours;
    if (coding.by_candidates && report) report->candidates = std::move(cand);
  }
  // Hole caps are judged against the input only where the level follows it;
  // coarser levels keep the border rule alone.
  if (kind == Kind::surface && !border.empty() && in.surface && in.surface_points && !in.approximate)
    best.drops = hole_faces(points, dt, best, *in.surface_points, *in.surface, reference_diagonal(points, in));
  if (report) {
    report->mismatches_before_toggles = best_mismatch;
    report->side_bits_estimate = best_bits;
    report->labels = std::move(best_labels);
  }
  return best;
}

}  // namespace hmc::detail
