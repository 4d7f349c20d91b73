// SPDX-License-Identifier: AGPL-3.0-or-later
// Inner-vertex layers, importance (eq. 3.1) and the labelling optimisers
// (thesis §3.4.2; rules in hierarchy.hpp).
#include <algorithm>

#include "encoder/hierarchy/hierarchy.hpp"
#include "encoder/hierarchy/internal.hpp"

namespace hmc::detail {

double importance(std::uint32_t max_degree, std::uint32_t degree, std::uint32_t total_layers,
                  std::uint32_t layer) noexcept {
  if (max_degree == 0 || total_layers == 0) return 0.0;
  const double d = (static_cast<double>(max_degree) - static_cast<double>(degree)) / static_cast<double>(max_degree);
  const double l =
      (static_cast<double>(total_layers) - static_cast<double>(layer)) / static_cast<double>(total_layers);
  return d * l;
}

double InnerAnalysis::ip(std::uint32_t v) const noexcept {
  if (layer[v] == kNoLayer) return 0.0;
  return importance(max_degree, degree[v], total_layers, layer[v]);
}

InnerAnalysis analyze_inner(const VertexGraph& g, const Classification& c) {
  const std::size_t n = g.size();
  InnerAnalysis a;
  a.layer.assign(n, kNoLayer);
  a.degree.resize(n);
  a.key.assign(n, 0);
  std::vector<std::uint32_t> queue;
  for (std::uint32_t v = 0; v < n; ++v) {
    a.degree[v] = g.degree(v);
    a.max_degree = std::max(a.max_degree, a.degree[v]);
    if (c.boundary[v]) {
      a.layer[v] = 0;
      queue.push_back(v);
    }
  }
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::uint32_t v = queue[head];
    a.total_layers = std::max(a.total_layers, a.layer[v] + 1);
    for (const std::uint32_t* u = g.begin(v); u != g.end(v); ++u)
      if (a.layer[*u] == kNoLayer) {
        a.layer[*u] = a.layer[v] + 1;
        queue.push_back(*u);
      }
  }
  for (std::uint32_t v = 0; v < n; ++v)
    if (a.layer[v] != kNoLayer)
      a.key[v] = static_cast<std::uint64_t>(a.max_degree - a.degree[v]) * (a.total_layers - a.layer[v]);
  return a;
}

namespace hierarchy {

namespace {

struct Variant {
  InnerOptimizer optimizer;
  std::uint32_t central;  // layer c of a central-layer variant, else 0
  std::vector<const std::vector<std::uint32_t>*> groups;
};

InnerOutcome run_variant(const VertexGraph& g, const InnerAnalysis& a, const Labelling& start,
                         const Variant& variant, std::size_t budget) {
  InnerOutcome out;
  out.labelling = start;
  out.chosen = variant.optimizer;
  out.central_layer = variant.central;
  std::size_t removed = 0;
  for (const auto* group : variant.groups)
    for (std::uint32_t v : *group) {
      if (removed >= budget) break;
      removed += out.labelling.try_remove(g, v);
    }
  for (std::uint32_t v = 0; v < g.size(); ++v)
    if (a.layer[v] != 0 && a.layer[v] != kNoLayer && out.labelling.label[v] != kRemoved) {
      out.key_sum += a.key[v];
      ++out.retained;
    }
  return out;
}

// Whether x has a strictly higher mean key than y (exact cross-multiplication).
bool better(const InnerOutcome& x, const InnerOutcome& y) {
  return x.key_sum * static_cast<UInt128>(y.retained) > y.key_sum * static_cast<UInt128>(x.retained);
}

}  // namespace

InnerOutcome run_inner(const VertexGraph& g, const InnerAnalysis& a, const Labelling& start, InnerOptimizer opt,
                       std::size_t budget) {
  // Inner vertices by layer (1 .. deepest), each in ascending (key, index).
  const std::uint32_t deepest = a.total_layers == 0 ? 0 : a.total_layers - 1;
  std::vector<std::vector<std::uint32_t>> layers(deepest + 1);
  std::vector<std::uint32_t> pool;
  for (std::uint32_t v = 0; v < g.size(); ++v)
    if (a.layer[v] != 0 && a.layer[v] != kNoLayer) {
      layers[a.layer[v]].push_back(v);
      pool.push_back(v);
    }
  auto by_key = [&a](std::uint32_t x, std::uint32_t y) { return a.key[x] != a.key[y] ? a.key[x] < a.key[y] : x < y; };
  for (auto& l : layers) std::sort(l.begin(), l.end(), by_key);
  std::sort(pool.begin(), pool.end(), by_key);

  std::vector<Variant> variants;
  auto want = [opt](InnerOptimizer o) { return opt == o || opt == InnerOptimizer::best; };
  if (want(InnerOptimizer::forward)) {
    Variant v{InnerOptimizer::forward, 0, {}};
    for (std::uint32_t k = 1; k <= deepest; ++k) v.groups.push_back(&layers[k]);
    variants.push_back(std::move(v));
  }
  if (want(InnerOptimizer::backward)) {
    Variant v{InnerOptimizer::backward, 0, {}};
    for (std::uint32_t k = deepest; k >= 1; --k) v.groups.push_back(&layers[k]);
    variants.push_back(std::move(v));
  }
  if (want(InnerOptimizer::greedy)) variants.push_back(Variant{InnerOptimizer::greedy, 0, {&pool}});
  if (opt == InnerOptimizer::best)
    for (std::uint32_t c = 2; c < deepest; ++c) {
      Variant v{InnerOptimizer::best, c, {}};
      for (std::uint32_t k = c; k <= deepest; ++k) v.groups.push_back(&layers[k]);
      for (std::uint32_t k = c - 1; k >= 1; --k) v.groups.push_back(&layers[k]);
      variants.push_back(std::move(v));
    }

  InnerOutcome best;
  bool have = false;
  for (const auto& variant : variants) {
    InnerOutcome o = run_variant(g, a, start, variant, budget);
    if (!have || better(o, best)) {
      best = std::move(o);
      have = true;
    }
  }
  return best;
}

}  // namespace hierarchy
}  // namespace hmc::detail
