// SPDX-License-Identifier: AGPL-3.0-or-later
#include <algorithm>
#include <string>

#include "codec/format.hpp"
#include "delaunay/delaunay.hpp"
#include "reconstruct/tuning.hpp"
#include "reconstruct/winding.hpp"
#include "pointset/octree.hpp"
#include "quant/scalar_quantizer.hpp"
#include "util/bytes.hpp"
#include "util/error.hpp"

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

// The input's connectivity on the grid: indices into the canonical points,
// elements with merged vertices dropped.
struct InputOnGrid {
  std::vector<Triangle> surface;  // triangles, or the boundary of the tetrahedra
  std::vector<std::uint32_t> border;  // vertices on border edges of an open surface
};

InputOnGrid input_on_grid(const Mesh& input, const std::vector<GridPoint>& quantized,
                          const std::vector<GridPoint>& points) {
  std::vector<std::uint32_t> idx(quantized.size());
  for (std::size_t i = 0; i < quantized.size(); ++i)
    idx[i] = static_cast<std::uint32_t>(std::lower_bound(points.begin(), points.end(), quantized[i]) - points.begin());
  InputOnGrid g;
  std::vector<Vec3> gp(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) gp[i] = {double(points[i][0]), double(points[i][1]), double(points[i][2])};
  if (!input.triangles.empty()) {
    for (const auto& t : input.triangles) {
      const Triangle f{idx[t[0]], idx[t[1]], idx[t[2]]};
      if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) g.surface.push_back(f);
    }
    // Border edges: used by one triangle only.
    std::vector<std::uint64_t> edges;
    for (const auto& f : g.surface)
      for (int k = 0; k < 3; ++k) {
        const std::uint64_t a = std::min(f[k], f[(k + 1) % 3]), b = std::max(f[k], f[(k + 1) % 3]);
        edges.push_back((a << 32) | b);
      }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i;
      while (j < edges.size() && edges[j] == edges[i]) ++j;
      if (j - i == 1) {
        g.border.push_back(static_cast<std::uint32_t>(edges[i] >> 32));
        g.border.push_back(static_cast<std::uint32_t>(edges[i] & 0xffffffffu));
      }
      i = j;
    }
    std::sort(g.border.begin(), g.border.end());
    g.border.erase(std::unique(g.border.begin(), g.border.end()), g.border.end());
  } else if (!input.tetrahedra.empty()) {
    std::vector<Tetrahedron> tets;
    for (const auto& t : input.tetrahedra) {
      const Tetrahedron f{idx[t[0]], idx[t[1]], idx[t[2]], idx[t[3]]};
      auto s = f;
      std::sort(s.begin(), s.end());
      if (s[0] != s[1] && s[1] != s[2] && s[2] != s[3]) tets.push_back(f);
    }
    g.surface = boundary_faces(gp, tets);
  }
  return g;
}

std::vector<std::uint8_t> info_payload(const EncodeReport& r) {
  std::string s = std::string("encoder=hmc ") + version_string() + "\n";
  s += "input_points=" + std::to_string(r.input_points) + "\n";
  s += "duplicates_merged=" + std::to_string(r.duplicates_merged) + "\n";
  return {s.begin(), s.end()};
}

Encoded encode_impl(const Mesh& input, const EncodeOptions& options) {
  check_connectivity(input);
  Encoded out;
  EncodeReport& rep = out.report;
  rep.kind = options.kind ? *options.kind : detect_kind(input);
  if (static_cast<int>(rep.kind) > 2) fail(Status::invalid_argument, "unknown kind");
  rep.quantizer = fit_quantizer(input.points, options.bits);
  const auto quantized = quantize(input.points, rep.quantizer);
  out.points = quantized;
  sort_canonical(out.points);
  out.points.erase(std::unique(out.points.begin(), out.points.end()), out.points.end());
  rep.input_points = input.points.size();
  rep.distinct_points = out.points.size();
  rep.duplicates_merged = rep.input_points - rep.distinct_points;

  Header header;
  header.kind = rep.kind;
  header.points = {rep.distinct_points};

  ContainerWriter w;
  w.chunk(kHead, header.write());
  w.chunk(kScalarQuantizer, write_scalar_quantizer(rep.quantizer));
  if (options.write_info) w.chunk(kInfo, info_payload(rep));

  const std::size_t before = w.size();
  ByteWriter base;
  base.u8(static_cast<std::uint8_t>(BaseCoder::octree));
  base.bytes(encode_octree(out.points, rep.quantizer.bits));
  w.chunk(kBaseLayer, base.data());
  LevelReport level;
  level.lod = 0;
  level.points = level.new_points = rep.distinct_points;
  level.layer_bytes = w.size() - before;

  if (rep.kind != Kind::points) {
    const auto grid = input_on_grid(input, quantized, out.points);
    const auto dt = delaunay(out.points);
    std::vector<Vec3> gp(out.points.size());
    for (std::size_t i = 0; i < gp.size(); ++i)
      gp[i] = {double(out.points[i][0]), double(out.points[i][1]), double(out.points[i][2])};
    std::vector<std::uint8_t> truth;
    if (!grid.surface.empty()) truth = truth_labels(out.points, dt, gp, grid.surface, grid.surface);
    TuningReport tr;
    TuneInput ti;
    ti.truth = std::move(truth);
    if (rep.kind == Kind::surface) ti.border = grid.border;
    ti.surface_points = &gp;
    ti.surface = &grid.surface;
    const ReconParams params = tune(out.points, dt, rep.kind, ti, options.fidelity, &tr);
    const std::size_t side_start = w.size();
    w.chunk(kRecon, write_recon(params));
    level.side_bytes = w.size() - side_start;
    level.label_corrections = params.toggles.size();
    level.rule_mismatches = tr.mismatches_before_toggles;
    auto rec = reconstruct(out.points, dt, rep.kind, params);
    out.triangles = std::move(rec.triangles);
    out.tetrahedra = std::move(rec.tetrahedra);
  }
  level.stream_bytes = w.size();
  rep.levels.push_back(level);

  w.chunk(kEnd, {});
  out.bytes = w.finish();
  rep.total_bytes = out.bytes.size();
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

const char* version_string() noexcept { return HMC_VERSION_STRING; }

Result<Encoded> encode(const Mesh& input, const EncodeOptions& options) {
  return guarded<Result<Encoded>>([&] { return Result<Encoded>(encode_impl(input, options)); });
}

}  // namespace hmc
