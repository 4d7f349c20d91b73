// SPDX-License-Identifier: AGPL-3.0-or-later
// Vertex graph of a level and the initial labelling (components).
#include <algorithm>

#include "encoder/hierarchy/hierarchy.hpp"
#include "encoder/hierarchy/internal.hpp"

namespace hmc::detail {

namespace {

using hierarchy::usable;

template <std::size_t N>
void collect_edges(const std::vector<std::array<std::uint32_t, N>>& simplices, std::size_t n,
                   std::vector<std::uint64_t>& edges) {
  edges.reserve(simplices.size() * N * (N - 1) / 2);
  for (const auto& s : simplices) {
    if (!usable(s, n)) continue;
    for (std::size_t i = 0; i < N; ++i)
      for (std::size_t j = i + 1; j < N; ++j) {
        const std::uint64_t a = std::min(s[i], s[j]), b = std::max(s[i], s[j]);
        edges.push_back(a << 32 | b);
      }
  }
}

}  // namespace

VertexGraph vertex_graph(const LevelMesh& m, Kind kind) {
  const std::size_t n = hierarchy::point_count(m);
  std::vector<std::uint64_t> edges;
  if (kind == Kind::surface) collect_edges(m.triangles, n, edges);
  if (kind == Kind::volume) collect_edges(m.tetrahedra, n, edges);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

  VertexGraph g;
  g.offset.assign(n + 1, 0);
  for (std::uint64_t e : edges) {
    ++g.offset[(e >> 32) + 1];
    ++g.offset[(e & 0xFFFFFFFFu) + 1];
  }
  for (std::size_t v = 0; v < n; ++v) g.offset[v + 1] += g.offset[v];
  g.nbr.resize(edges.size() * 2);
  std::vector<std::uint32_t> fill(g.offset.begin(), g.offset.end() - 1);
  // Smaller neighbours first (ascending a for each b), then larger ones
  // (ascending b for each a): every list comes out sorted.
  for (std::uint64_t e : edges) {
    const auto a = static_cast<std::uint32_t>(e >> 32), b = static_cast<std::uint32_t>(e & 0xFFFFFFFFu);
    g.nbr[fill[b]++] = a;
  }
  for (std::uint64_t e : edges) {
    const auto a = static_cast<std::uint32_t>(e >> 32), b = static_cast<std::uint32_t>(e & 0xFFFFFFFFu);
    g.nbr[fill[a]++] = b;
  }
  return g;
}

namespace hierarchy {

Labelling initial_labelling(const VertexGraph& g, std::size_t min_keep) {
  const std::size_t n = g.size();
  Labelling l;
  l.min_keep = min_keep;
  l.label.assign(n, kFree);
  l.component.assign(n, 0xFFFFFFFFu);
  std::vector<std::uint32_t> queue;
  for (std::uint32_t s = 0; s < n; ++s) {
    if (l.component[s] != 0xFFFFFFFFu) continue;
    const auto id = static_cast<std::uint32_t>(l.component_left.size());
    queue.assign(1, s);
    l.component[s] = id;
    for (std::size_t head = 0; head < queue.size(); ++head)
      for (const std::uint32_t* u = g.begin(queue[head]); u != g.end(queue[head]); ++u)
        if (l.component[*u] == 0xFFFFFFFFu) {
          l.component[*u] = id;
          queue.push_back(*u);
        }
    l.component_left.push_back(queue.size());
    if (g.degree(s) == 0) l.label[s] = kFixed;
  }
  return l;
}

}  // namespace hierarchy
}  // namespace hmc::detail
