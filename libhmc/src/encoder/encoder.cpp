// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <future>
#include <map>
#include <optional>
#include <string>

#include "codec/format.hpp"
#include "encoder/input_grid.hpp"
#include "encoder/hierarchy/hierarchy.hpp"
#include "pointset/refine.hpp"
#include "delaunay/delaunay.hpp"
#include "encoder/tuning.hpp"
#include "encoder/winding.hpp"
#include "pointset/octree.hpp"
#include "quant/scalar_quantizer.hpp"
#include "util/bytes.hpp"
#include "util/error.hpp"
#include "util/helpers.hpp"
#include "util/kdtree.hpp"
#include "util/morton.hpp"

namespace hmc {

namespace {

using namespace detail;

void check_connectivity(const Mesh& m) {
  const auto n = m.points.size();
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    for (auto v : m.triangles[i])
      if (v >= n)
        fail(Status::invalid_argument, "triangle " + std::to_string(i) + " uses vertex " + std::to_string(v) +
                                           ", there are " + std::to_string(n));
  for (std::size_t i = 0; i < m.tetrahedra.size(); ++i)
    for (auto v : m.tetrahedra[i])
      if (v >= n)
        fail(Status::invalid_argument, "tetrahedron " + std::to_string(i) + " uses vertex " + std::to_string(v) +
                                           ", there are " + std::to_string(n));
}

Kind detect_kind(const Mesh& m) {
  if (!m.tetrahedra.empty()) return Kind::volume;
  if (!m.triangles.empty()) return Kind::surface;
  return Kind::points;
}

// What the stream does not say itself: the encoder and, when quantization
// merged points, how many the input had (otherwise the finest level's count).
std::vector<std::uint8_t> info_payload(const EncodeReport& r) {
  std::string s = std::string("encoder=hmc ") + version_string() + "\n";
  if (r.duplicates_merged > 0) {
    s += "input_points=" + std::to_string(r.input_points) + "\n";
    s += "duplicates_merged=" + std::to_string(r.duplicates_merged) + "\n";
  }
  return {s.begin(), s.end()};
}

// One level as the encoder plans it.
struct LevelPlan {
  std::vector<GridPoint> points;   // canonical
  std::vector<GridPoint> added;    // points this level adds to the next coarser one
  ReconParams params;
  Reconstruction rec;
  LevelReport report;
};

detail::BoundaryMode to_detail(hmc::BoundaryMode m) {
  return m == hmc::BoundaryMode::linear     ? detail::BoundaryMode::linear
         : m == hmc::BoundaryMode::adaptive ? detail::BoundaryMode::adaptive
                                            : detail::BoundaryMode::constant;
}
detail::InnerOptimizer to_detail(Optimizer o) {
  switch (o) {
    case Optimizer::forward: return detail::InnerOptimizer::forward;
    case Optimizer::backward: return detail::InnerOptimizer::backward;
    case Optimizer::greedy: return detail::InnerOptimizer::greedy;
    case Optimizer::best: break;
  }
  return detail::InnerOptimizer::best;
}
Optimizer from_detail(detail::InnerOptimizer o) {
  switch (o) {
    case detail::InnerOptimizer::forward: return Optimizer::forward;
    case detail::InnerOptimizer::backward: return Optimizer::backward;
    case detail::InnerOptimizer::greedy: return Optimizer::greedy;
    case detail::InnerOptimizer::best: break;
  }
  return Optimizer::best;
}

// Indices of `points` (canonical) in `level` (canonical subset), or ~0u.
std::vector<std::uint32_t> index_in(const std::vector<GridPoint>& points, const std::vector<GridPoint>& level) {
  std::vector<std::uint32_t> idx(points.size(), ~0u);
  std::size_t j = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    while (j < level.size() && level[j] < points[i]) ++j;
    if (j < level.size() && level[j] == points[i]) idx[i] = static_cast<std::uint32_t>(j);
  }
  return idx;
}

// Where the input stands on a level whose points are not all input points
// (a level of octree cells, clustered_target): each finest input point's
// index in the level (~0u: not in it) and position (grid units), and the
// input surface carried over to those positions.
struct CarriedTarget {
  std::vector<std::uint32_t> index;
  std::vector<Vec3> positions;
  std::vector<Triangle> surface;  // the input's faces (finest indices), those that do not collapse
};

// Reconstruction side information and result for one level. The target is
// the input surface: at its own points when the level's points are input
// points, carried over to the level's points otherwise (`carried`, a level
// of octree cells): the encoder knows where each input point went, so it
// tunes against that surface just as for a level of input points. Coarser
// levels only approximate the input: unless the fidelity is exact, they
// keep the rule's labels and let the decoder's repair mend what makes the
// surface unsound; when `fit` (fit_coarse_levels, levels of octree cells)
// they follow the input as the finest level does, aiming at its topology.
void plan_reconstruction(LevelPlan& plan, const Tetrahedralization& dt, Kind kind, const InputOnGrid& fine,
                         const std::vector<GridPoint>& fine_points, const std::vector<Vec3>& fine_gp,
                         const EncodeOptions& options, bool fit, const LevelPlan* finest,
                         const CarriedTarget* carried = nullptr,
                         WindingCache* winding = nullptr, HelperBudget* helpers = nullptr) {
  const Fidelity fidelity = options.fidelity;
  const bool coarser = finest != nullptr;
  const auto idx = carried ? carried->index : index_in(fine_points, plan.points);
  const std::vector<Vec3>& surface_gp = carried ? carried->positions : fine_gp;
  const std::vector<Triangle>& surface = carried ? carried->surface : fine.surface;
  std::vector<Triangle> faces;  // input faces whose vertices all survive, on this level
  for (const auto& f : surface) {
    const Triangle g{idx[f[0]], idx[f[1]], idx[f[2]]};
    if (g[0] != ~0u && g[1] != ~0u && g[2] != ~0u && g[0] != g[1] && g[1] != g[2] && g[0] != g[2]) faces.push_back(g);
  }
  const std::array<std::uint32_t, 6>* seal = options.seal_box ? &*options.seal_box : nullptr;
  TuneInput ti;
  double unsure = 0;
  if (!surface.empty())
    ti.truth = truth_labels(plan.points, dt, surface_gp, surface, faces, carried ? nullptr : winding, false, &unsure, seal);
  if (kind == Kind::surface) {
    // Level indices: ascending (RCON gap-codes the list) and distinct. A
    // cell level's points are not in the input's order.
    for (auto v : fine.border)
      if (idx[v] != ~0u) ti.border.push_back(idx[v]);
    std::sort(ti.border.begin(), ti.border.end());
    ti.border.erase(std::unique(ti.border.begin(), ti.border.end()), ti.border.end());
  }
  ti.surface_points = &surface_gp;
  ti.surface = &surface;
  ti.helpers = helpers;
  ti.diagonal = options.tolerance_diagonal;
  if (options.seal_box) {
    ti.seal = true;
    ti.seal_box = *options.seal_box;
  }
  // Coarser levels only approximate the input; exact fidelity still follows
  // it, and so does any fidelity but the rule's when asked to fit them.
  ti.approximate = coarser && fidelity != Fidelity::exact && !(fit && fidelity != Fidelity::rule);
  const bool closed = kind == Kind::volume || fine.border.empty();
  if (!ti.approximate && (carried || ((fidelity == Fidelity::shape || fidelity == Fidelity::topology) && closed))) {
    // The target can be unsound (a cell level's carried surface folds where
    // points moved; input triangles missing from the Delaunay leave pinches
    // and non-manifold edges): tuning mends the labels it gives and aims at
    // the input's topology (closed inputs only: the interface of an open one
    // is closed by the labelling's caps). Exact fidelity on exact levels
    // keeps the input's labels as they are; so does an open input surface on
    // an exact level, where mending without a topology to aim at opens more
    // holes than it closes (the bunny: 41 more border edges).
    ti.clean_target = true;
    if (closed) {
      // A fitted coarser level aims at the whole input's topology: the input
      // faces whose vertices all survive on it are only a patchwork.
      const auto [components, euler] = surface_topology(coarser && fit ? surface : faces);
      ti.target_components = components;
      ti.target_euler = euler;
    }
  }
  TuningReport tr;
  plan.params = tune(plan.points, dt, kind, ti, fidelity, &tr);
  // An open surface whose winding numbers leave many labels open is a
  // sheet rather than a solid with holes (the Stanford bunny leaves 0.4 %
  // open, a height field 99 %): plan it read as a sheet too (truth_labels)
  // and keep whichever sends less side information. A generated
  // 1,600-point height field at q = 12: side information 13.5 -> 7.9 bits
  // per point, 78 % -> 95 % of the reachable triangles.
  if (kind == Kind::surface && !coarser && !carried && !fine.border.empty() && unsure > kSheetUnsure) {
    TuneInput sheet = ti;
    sheet.truth = truth_labels(plan.points, dt, surface_gp, surface, faces, winding, true, nullptr, seal);
    TuningReport sheet_tr;
    ReconParams sheet_params = tune(plan.points, dt, kind, sheet, fidelity, &sheet_tr);
    if (write_recon(sheet_params).size() < write_recon(plan.params).size()) {
      plan.params = std::move(sheet_params);
      tr = std::move(sheet_tr);
    }
  }
  plan.rec = tr.labels.empty() ? reconstruct(plan.points, dt, kind, plan.params)
                               : reconstruct_from_labels(dt, kind, plan.params, std::move(tr.labels), &tr.candidates);
  plan.report.label_corrections = tr.corrections;
  plan.report.rule_mismatches = tr.mismatches_before_toggles;
}

// The input surface as a level of octree cells would draw it, the target of
// its reconstruction: each input point merged into the
// level's point nearest to it, the faces that do not collapse kept. Few
// input faces keep all three vertices on such a level, so those alone
// would be no target.
CarriedTarget clustered_target(const std::vector<GridPoint>& level, const std::vector<GridPoint>& fine_points,
                             const InputOnGrid& fine) {
  std::vector<KdTree<std::int64_t>::Point> ip;
  ip.reserve(level.size());
  for (const auto& p : level) ip.push_back({std::int64_t{p[0]}, std::int64_t{p[1]}, std::int64_t{p[2]}});
  const KdTree<std::int64_t> tree(ip);
  CarriedTarget target;
  target.index.resize(fine_points.size());
  target.positions.resize(fine_points.size());
  for (std::size_t f = 0; f < fine_points.size(); ++f) {
    const auto& p = fine_points[f];
    const auto at = static_cast<std::uint32_t>(tree.nearest({std::int64_t{p[0]}, std::int64_t{p[1]}, std::int64_t{p[2]}}).index);
    target.index[f] = at;
    target.positions[f] = {double(level[at][0]), double(level[at][1]), double(level[at][2])};
  }
  // Faces on one input point per level point (the first merged into it):
  // the same triangles in space, but the merged surface's edges then match
  // as a closed surface's do, and faces that merge onto the same level
  // triangle with opposite orientations cancel (the winding number is their
  // sum). With the input's own indices each merged edge stayed a border
  // edge, and truth_labels' caps over them (as many as the surface's
  // triangles) made a 20,000-point torus's preview levels about 30 times slower
  // to plan than its finest level.
  std::vector<std::uint32_t> representative(level.size(), ~0u);
  for (std::size_t f = 0; f < fine_points.size(); ++f)
    if (representative[target.index[f]] == ~0u) representative[target.index[f]] = static_cast<std::uint32_t>(f);
  std::map<Triangle, int> net;  // level triangle (smallest index first) -> signed count
  for (const auto& t : fine.surface) {
    Triangle g{target.index[t[0]], target.index[t[1]], target.index[t[2]]};
    if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2]) continue;
    while (g[0] > g[1] || g[0] > g[2]) g = {g[1], g[2], g[0]};  // rotate, orientation kept
    int sign = 1;
    if (g[1] > g[2]) {
      std::swap(g[1], g[2]);
      sign = -1;
    }
    net[g] += sign;
  }
  for (const auto& [g, n] : net)
    for (int m = 0; m < std::abs(n); ++m)
      target.surface.push_back(n > 0 ? Triangle{representative[g[0]], representative[g[1]], representative[g[2]]}
                                     : Triangle{representative[g[0]], representative[g[2]], representative[g[1]]});
  return target;
}

// The RCON payload of a level: its border as a change to the coarser
// level's (flag bit 3) when that is shorter, as with an open surface whose
// border points mostly survive into the coarser levels.
std::vector<std::uint8_t> recon_payload(const ReconParams& params, const std::vector<GridPoint>& points,
                                        const LevelPlan* coarser) {
  auto full = write_recon(params);
  if (!coarser || (params.border.empty() && coarser->params.border.empty())) return full;
  ReconParams coded = params;
  coded.border = border_change(params.border, inherited_border(points, coarser->points, coarser->params.border));
  coded.border_delta = true;
  auto delta = write_recon(coded);
  return delta.size() < full.size() ? delta : full;
}

// With a helper thread free (EncodeOptions::threads > 1), each point layer
// is coded there as soon as its two levels are known (a refinement layer
// once its level is decimated, the base layer when the coarsest level's
// planning starts), beside the planning of the coarser levels, which is most
// of the work. A job gives the bytes the same call gives on the caller's
// thread, and take() rethrows an error it meets; a layer whose job could not
// start (no helper free) is coded by the caller when it is written.
class LayerJobs {
 public:
  explicit LayerJobs(HelperBudget& helpers) : helpers_(helpers) {}
  LayerJobs(const LayerJobs&) = delete;
  LayerJobs& operator=(const LayerJobs&) = delete;
  ~LayerJobs() {
    for (auto& [index, job] : jobs_) job.wait();
  }
  template <class Job>
  void start(std::size_t index, Job job) {
    auto f = helpers_.try_run(std::move(job));
    if (f.valid()) jobs_[index] = std::move(f);
  }
  std::optional<RefinementLayer> take(std::size_t index) {
    auto it = jobs_.find(index);
    if (it == jobs_.end()) return std::nullopt;
    auto job = std::move(it->second);
    jobs_.erase(it);
    return job.get();
  }

 private:
  HelperBudget& helpers_;
  std::map<std::size_t, std::future<RefinementLayer>> jobs_;
};

// A level of octree cells (EncodeOptions::preview_ratio): the points of
// `points` (more than one) to remove so that one per occupied octree cell
// stays, the one nearest the cell's centre (ties: the first in canonical
// order), at the finest depth d (cells of side 2^(q-d)) whose occupied
// cells are at most half the points.
DecimationResult octree_cells(const std::vector<GridPoint>& points, int q) {
  const double budget = 0.5 * static_cast<double>(points.size());
  std::vector<std::uint64_t> keys(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) keys[i] = morton_key(points[i], q);
  // Cells at depth d are the distinct keys >> 3(q - d); a shift keeps the
  // sorted order, so one sorted copy counts them at every depth.
  std::vector<std::uint64_t> sorted = keys;
  std::sort(sorted.begin(), sorted.end());
  auto cells_at = [&](int d) {
    const int s = 3 * (q - d);
    std::size_t n = 0;
    for (std::size_t i = 0; i < sorted.size(); ++i) n += i == 0 || (sorted[i] >> s) != (sorted[i - 1] >> s);
    return n;
  };
  int d = 0;
  while (d < q && static_cast<double>(cells_at(d + 1)) <= budget) ++d;
  const int shift = q - d;
  // Doubled coordinates: a cell's centre is 2c + 1 cells of half its side.
  std::map<std::uint64_t, std::pair<std::uint64_t, std::size_t>> best;  // cell -> (squared distance, index)
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::uint64_t cell = keys[i] >> (3 * shift);
    std::uint64_t dist = 0;
    for (int a = 0; a < 3; ++a) {
      if (shift == 0) break;
      const std::int64_t p = std::int64_t{points[i][a]} * 2;
      const std::int64_t c = ((std::int64_t{points[i][a]} >> shift) << (shift + 1)) + (std::int64_t{1} << shift);
      dist += static_cast<std::uint64_t>((p - c) * (p - c));
    }
    auto [it, fresh] = best.try_emplace(cell, dist, i);
    if (!fresh && dist < it->second.first) it->second = {dist, i};
  }
  DecimationResult dr;
  dr.removed.assign(points.size(), true);
  for (const auto& [cell, kept] : best) dr.removed[kept.second] = false;
  return dr;
}

Encoded encode_impl(const Mesh& input, const EncodeOptions& options) {
  check_connectivity(input);
  if (options.levels < 1 || options.levels > static_cast<int>(kMaxLevels))
    fail(Status::invalid_argument, "levels must be between 1 and 64, got " + std::to_string(options.levels));
  if (!(options.removal_ratio > 0 && options.removal_ratio <= 1))
    fail(Status::invalid_argument, "removal ratio must be in (0, 1]");
  if (!(options.preview_ratio >= 0 && options.preview_ratio < 1))
    fail(Status::invalid_argument, "preview ratio must be in [0, 1)");
  if (!(options.tolerance_diagonal >= 0 && std::isfinite(options.tolerance_diagonal)))
    fail(Status::invalid_argument, "tolerance diagonal must be finite and >= 0");
  if (options.seal_box) {
    const auto& b = *options.seal_box;
    const std::uint64_t size = options.bits >= 1 && options.bits <= 21 ? std::uint64_t{1} << options.bits : kSealBound;
    for (int ax = 0; ax < 3; ++ax)
      if (b[ax] >= b[3 + ax] || b[3 + ax] > size)
        fail(Status::invalid_argument, "seal box: axis " + std::to_string(ax) + " [" + std::to_string(b[ax]) + ", " +
                                           std::to_string(b[3 + ax]) + ") is empty or beyond the lattice (2^" +
                                           std::to_string(options.bits) + ")");
  }
  Encoded out;
  EncodeReport& rep = out.report;
  rep.kind = options.kind ? *options.kind : detect_kind(input);
  if (static_cast<int>(rep.kind) > 2) fail(Status::invalid_argument, "unknown kind");
  rep.quantizer = options.lattice ? lattice_quantizer(input.points, options.bits, options.lattice->origin, options.lattice->step)
                                  : fit_quantizer(input.points, options.bits);
  const int q = rep.quantizer.bits;
  const auto quantized = quantize(input.points, rep.quantizer);
  std::vector<GridPoint> fine_points = quantized;
  sort_canonical(fine_points);
  fine_points.erase(std::unique(fine_points.begin(), fine_points.end()), fine_points.end());
  rep.input_points = input.points.size();
  rep.distinct_points = fine_points.size();
  rep.duplicates_merged = rep.input_points - rep.distinct_points;

  const InputOnGrid fine = input_on_grid(input, quantized, fine_points);
  std::vector<Vec3> fine_gp(fine_points.size());
  for (std::size_t i = 0; i < fine_gp.size(); ++i)
    fine_gp[i] = {double(fine_points[i][0]), double(fine_points[i][1]), double(fine_points[i][2])};

  // Plan the levels, finest first.
  std::vector<LevelPlan> plans;
  DecimationState state;
  std::vector<GridPoint> current = fine_points;
  // Work per level shrinks with its point count; report progress by points.
  double work_done = 0, work_total = 0;
  for (int k = 0; k < options.levels; ++k) work_total += std::pow(1.0 - 0.5 * options.removal_ratio, k);
  auto progress = [&](int level, double share) {
    if (options.progress) options.progress(level, std::min(1.0, (work_done + share) / work_total));
  };
  HelperBudget helpers(options.threads);  // outlives every job below
  WindingCache winding;  // the input surface's winding numbers, from one level to the next
  winding.helpers = &helpers;
  LayerJobs jobs(helpers);
  const BaseCoder base_coder = options.fast_decode ? BaseCoder::octree : BaseCoder::ranked;
  std::string stopped;  // why a level before the last requested one is the coarsest
  // EncodeOptions::preview_ratio: below the independent-set levels, levels
  // of octree cells until one holds at most this many points.
  const double preview_points = options.preview_ratio * static_cast<double>(fine_points.size());
  bool of_cells = false;  // the level being planned is made of octree cells
  for (int k = 0; k < static_cast<int>(kMaxLevels); ++k) {
    progress(std::min(k, options.levels - 1), 0);
    LevelPlan plan;
    plan.points = std::move(current);
    current.clear();
    plan.report.lod = k;
    const bool by_cells = k + 1 >= options.levels;  // the next coarser level, if any, is made of octree cells
    const bool more = plan.points.size() > 4 && k + 1 < static_cast<int>(kMaxLevels) &&
                      (!by_cells || (options.preview_ratio > 0 && static_cast<double>(plan.points.size()) > preview_points));
    if (!more)  // the coarsest level: its points are the base layer's
      jobs.start(plans.size(), [points = plan.points, q, base_coder] {
        return RefinementLayer{0, encode_base(points, q, base_coder)};
      });
    Tetrahedralization dt;
    if (rep.kind != Kind::points || more) dt = delaunay(plan.points);
    if (rep.kind != Kind::points) {
      std::optional<CarriedTarget> clustered;
      // Levels of octree cells are few points: fitting them to the input
      // costs little (2 % of the stream on the shared models) and makes the
      // preview look like the model.
      if (of_cells && options.fidelity != Fidelity::rule) clustered = clustered_target(plan.points, fine_points, fine);
      plan_reconstruction(plan, dt, rep.kind, fine, fine_points, fine_gp, options,
                          options.fit_coarse_levels || of_cells, k > 0 ? &plans.front() : nullptr,
                          clustered ? &*clustered : nullptr, &winding, &helpers);
    }
    if (more) {
      LevelMesh mesh;
      mesh.points = &plan.points;
      DecimationOptions dopt;
      dopt.kind = rep.kind == Kind::surface ? Kind::surface : Kind::volume;
      if (rep.kind == Kind::surface) {
        mesh.triangles = plan.rec.triangles;
      } else {
        // Points are decimated as the volume their Delaunay tetrahedra fill.
        mesh.tetrahedra = rep.kind == Kind::volume ? plan.rec.tetrahedra : dt.tets;
      }
      dopt.target_ratio = options.removal_ratio;
      dopt.boundary = to_detail(options.boundary_mode);
      dopt.optimizer = to_detail(options.optimizer);
      dopt.level = k;
      const DecimationResult dr = by_cells ? octree_cells(plan.points, q) : decimate(mesh, dopt, state);
      auto& lr = plan.report;
      lr.boundary_removed = dr.boundary_removed;
      lr.inner_removed = dr.inner_removed;
      lr.classification_disagreements = dr.classification.disagreements;
      lr.dmax = dr.dmax;
      lr.optimizer = from_detail(dr.chosen);
      lr.mean_importance_retained = dr.mean_ip_retained;
      for (const auto& l : dr.layers) lr.layer_sizes.push_back(l.vertices);
      for (std::size_t i = 0; i < plan.points.size(); ++i)
        (dr.removed[i] ? plan.added : current).push_back(plan.points[i]);
      if (plan.added.empty()) current.clear();
      if (!plan.added.empty() && !current.empty())
        jobs.start(plans.size(), [coarse = current, added = plan.added, q, fast = options.fast_decode] {
          return encode_refinement_layer(coarse, added, q, fast);
        });
    }
    plan.report.simplices = rep.kind == Kind::surface ? plan.rec.triangles.size() : plan.rec.tetrahedra.size();
    if (k + 1 < options.levels && current.empty()) {
      const std::string simplices = rep.kind == Kind::surface ? "triangles" : "tetrahedra";
      const std::size_t n = plan.points.size();
      const bool unrebuilt = plan.report.simplices == 0 && rep.kind != Kind::points;
      stopped = !more                ? "it has " + std::to_string(n) + (n == 1 ? " point" : " points")
                : !plan.added.empty() ? std::string("the decimation would remove all its points")
                : dt.tets.empty()     ? std::string("its points span no volume")
                : unrebuilt           ? "its reconstruction has no " + simplices
                                      : std::string("the decimation found no point to remove");
    }
    if (k == 0 && rep.kind != Kind::points && dt.tets.empty())
      rep.notes.push_back("the " + std::to_string(plan.points.size()) +
                          " points span no volume (all coplanar or collinear on the grid): the decoder rebuilds "
                          "connectivity from their 3D Delaunay tetrahedralization, so it rebuilds no " +
                          (rep.kind == Kind::surface ? "triangles" : "tetrahedra"));
    plans.push_back(std::move(plan));
    of_cells = by_cells;
    work_done += std::pow(1.0 - 0.5 * options.removal_ratio, k);
    if (current.empty()) break;
  }
  progress(static_cast<int>(plans.size()) - 1, 1);
  // The input surface's winding trees served the planning only; the layers
  // coded below (on one thread, all of them) need their memory more.
  winding = WindingCache{};
  // The coarsest level adds nothing to a coarser one.
  plans.back().added.clear();
  const std::string written = std::to_string(plans.size()) + " of the " + std::to_string(options.levels) +
                              " levels requested";
  if (!stopped.empty())
    rep.notes.push_back(written + ": level " + std::to_string(plans.size() - 1) + " is the coarsest, as " + stopped);

  Header header;
  header.kind = rep.kind;
  for (auto it = plans.rbegin(); it != plans.rend(); ++it) header.points.push_back(it->points.size());

  ContainerWriter w;
  w.chunk(kHead, header.write());
  w.chunk(kScalarQuantizer, write_scalar_quantizer(rep.quantizer));
  if (options.write_info) w.chunk(kInfo, info_payload(rep));
  for (std::size_t i = plans.size(); i-- > 0;) {
    LevelPlan& plan = plans[i];
    LevelReport& level = plan.report;
    const std::size_t before = w.size();
    ByteWriter layer;
    std::optional<RefinementLayer> coded = jobs.take(i);
    if (i + 1 == plans.size()) {
      layer.bytes(coded ? coded->bytes : encode_base(plan.points, q, base_coder, &helpers));
      w.chunk(kBaseLayer, layer.data());
      level.new_points = plan.points.size();
    } else {
      const RefinementLayer refinement =
          coded ? std::move(*coded) : encode_refinement_layer(plans[i + 1].points, plans[i].added, q, options.fast_decode);
      layer.u8(refinement.coder);
      layer.bytes(refinement.bytes);
      w.chunk(kRefinement, layer.data());
      level.new_points = plans[i].added.size();
      level.coder = refinement.coder;
    }
    level.points = plan.points.size();
    level.layer_bytes = w.size() - before;
    if (rep.kind != Kind::points) {
      const std::size_t side_start = w.size();
      w.chunk(kRecon, recon_payload(plan.params, plan.points, i + 1 < plans.size() ? &plans[i + 1] : nullptr));
      level.side_bytes = w.size() - side_start;
    }
    level.stream_bytes = w.size();
    rep.levels.push_back(level);
    DecodedLevel dl;
    dl.lod = level.lod;
    dl.points = plan.points;
    dl.triangles = plan.rec.triangles;
    dl.tetrahedra = plan.rec.tetrahedra;
    dl.rebuilt = rep.kind != Kind::points;
    dl.stream_bytes = level.stream_bytes;
    out.levels.push_back(std::move(dl));
  }
  w.chunk(kEnd, {});
  out.bytes = w.finish();
  rep.total_bytes = out.bytes.size();
  out.points = std::move(plans.front().points);
  out.triangles = std::move(plans.front().rec.triangles);
  out.tetrahedra = std::move(plans.front().rec.tetrahedra);
  return out;
}

}  // namespace

const char* kind_name(Kind k) noexcept {
  switch (k) {
    case Kind::points: return "points";
    case Kind::surface: return "surface";
    case Kind::volume: return "volume";
  }
  return "unknown";
}

const char* boundary_mode_name(hmc::BoundaryMode m) noexcept {
  switch (m) {
    case hmc::BoundaryMode::constant: return "constant";
    case hmc::BoundaryMode::linear: return "linear";
    case hmc::BoundaryMode::adaptive: return "adaptive";
  }
  return "unknown";
}

const char* optimizer_name(Optimizer o) noexcept {
  switch (o) {
    case Optimizer::forward: return "forward";
    case Optimizer::backward: return "backward";
    case Optimizer::greedy: return "greedy";
    case Optimizer::best: return "best";
  }
  return "unknown";
}

Result<Encoded> encode(const Mesh& input, const EncodeOptions& options) {
  return guarded<Result<Encoded>>([&] { return Result<Encoded>(encode_impl(input, options)); });
}

Result<ScalarQuantizer> fit_lattice(const std::vector<Vec3>& points, int bits) {
  return guarded<Result<ScalarQuantizer>>([&] { return Result<ScalarQuantizer>(fit_quantizer(points, bits)); });
}

}  // namespace hmc
