// SPDX-License-Identifier: AGPL-3.0-or-later
// One level of decimation: budgets, Dmax selection, boundary phase, then the
// inner phase (rules in hierarchy.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "encoder/hierarchy/hierarchy.hpp"
#include "encoder/hierarchy/internal.hpp"

namespace hmc::detail {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::size_t budget(double ratio, std::size_t count) {
  return static_cast<std::size_t>(std::floor(ratio * static_cast<double>(count) + 0.5));
}

}  // namespace

DecimationResult decimate(const LevelMesh& m, const DecimationOptions& o, DecimationState& state) {
  using namespace hierarchy;
  const std::size_t n = point_count(m);
  const bool volume = o.kind == Kind::volume;
  const double ratio = o.target_ratio > 0 ? std::min(o.target_ratio, 1.0) : 0.0;  // NaN -> 0

  DecimationResult r;
  const VertexGraph g = vertex_graph(m, o.kind);
  r.classification = classify(m, o.kind);
  const Classification& c = r.classification;
  r.boundary_budget = budget(ratio, c.boundary_count);
  r.inner_budget = volume ? budget(ratio, n - c.boundary_count) : 0;
  Labelling lab = initial_labelling(g, volume ? 4 : 3);

  // ---- Boundary phase.
  const BoundaryAnalysis ba = analyze_boundary(m, o.kind, c, g, o.feature_angle_deg);
  std::vector<std::uint32_t> order;
  for (std::uint32_t v = 0; v < n; ++v)
    if ((ba.type[v] == BoundaryVertexType::simple || ba.type[v] == BoundaryVertexType::line) &&
        ba.error[v] < kInf)
      order.push_back(v);
  std::vector<double> rank(ba.error);
  if (o.boundary == BoundaryMode::adaptive && !order.empty()) {
    std::vector<double> h;
    for (std::uint32_t v : order) h.push_back(ba.local_length[v]);
    const std::size_t mid = (h.size() - 1) / 2;
    std::nth_element(h.begin(), h.begin() + static_cast<std::ptrdiff_t>(mid), h.end());
    const double median = h[mid];
    // A zero local length (coincident points) admits no sensible scale.
    for (std::uint32_t v : order) rank[v] = ba.local_length[v] > 0 ? rank[v] * median / ba.local_length[v] : kInf;
    order.erase(std::remove_if(order.begin(), order.end(), [&rank](std::uint32_t v) { return !(rank[v] < kInf); }),
                order.end());
  }
  std::sort(order.begin(), order.end(),
            [&rank](std::uint32_t x, std::uint32_t y) { return rank[x] != rank[y] ? rank[x] < rank[y] : x < y; });

  const bool select = o.boundary == BoundaryMode::adaptive || state.dmax0 < 0;
  double dmax = kInf;
  if (!select) {
    const double factor = o.boundary == BoundaryMode::linear ? std::max(1.0, 1.0 + (o.level - state.first_level)) : 1.0;
    dmax = state.dmax0 * factor;
  }
  double last = -1;
  for (std::uint32_t v : order) {
    if (r.boundary_removed >= r.boundary_budget || !(rank[v] < dmax)) break;
    if (lab.try_remove(g, v)) {
      ++r.boundary_removed;
      last = rank[v];
    }
  }
  if (select) {
    dmax = last < 0 ? 0.0 : std::nextafter(last, kInf);
    if (o.boundary != BoundaryMode::adaptive) {
      state.dmax0 = dmax;
      state.first_level = o.level;
    }
  }
  r.dmax = dmax;
  state.dmax_history.push_back(dmax);
  r.boundary_candidates = static_cast<std::size_t>(
      std::count_if(order.begin(), order.end(), [&](std::uint32_t v) { return rank[v] < dmax; }));

  // ---- Inner phase.
  InnerAnalysis ia;
  if (volume) {
    ia = analyze_inner(g, c);
    InnerOutcome io = run_inner(g, ia, lab, o.optimizer, r.inner_budget);
    lab = std::move(io.labelling);
    r.chosen = io.chosen;
    r.central_layer = io.central_layer;
    r.inner_removed = lab.removed - r.boundary_removed;
    if (io.retained > 0 && ia.max_degree > 0 && ia.total_layers > 0)
      r.mean_ip_retained = static_cast<double>(io.key_sum) / static_cast<double>(io.retained) /
                           (static_cast<double>(ia.max_degree) * static_cast<double>(ia.total_layers));
  } else {
    r.chosen = o.optimizer == InnerOptimizer::best ? InnerOptimizer::forward : o.optimizer;
  }

  r.removed.assign(n, 0);
  r.layers.assign(volume ? std::max<std::uint32_t>(ia.total_layers, 1) : 1, LayerStats{});
  for (std::uint32_t v = 0; v < n; ++v) {
    r.removed[v] = lab.label[v] == kRemoved;
    const std::uint32_t layer = volume && ia.layer[v] != kNoLayer ? ia.layer[v] : 0;
    ++r.layers[layer].vertices;
    r.layers[layer].removed += r.removed[v];
  }
  return r;
}

}  // namespace hmc::detail
