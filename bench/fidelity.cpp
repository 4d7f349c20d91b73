// SPDX-License-Identifier: AGPL-3.0-or-later
// Reconstruction fidelity of one model (issue 3's report): quantize, encode
// with reconstruction side information, decode, and compare the decoded
// connectivity with the input's own. Prints one JSON object.
//
// usage: fidelity MODEL [--bits Q] [--fidelity rule|topology|shape|exact]
//                       [--levels L] [--per-level] [--fit-coarse]
//                       [--preview-ratio R]
//
// With --levels the model goes through the public encoder and decoder
// instead, with L levels, and the report compares geometry and topology, not
// vertex identity: see stream_report().
// --per-level adds every decoded level's Hausdorff distance to the input
// surface (a volume's boundary), its topology and its side bytes;
// --fit-coarse encodes with EncodeOptions::fit_coarse_levels, --preview-ratio R with
// EncodeOptions::preview_ratio = R (levels of octree cells below the L levels).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numeric>
#include <set>
#include <string>

#include "codec/format.hpp"
#include "encoder/input_grid.hpp"
#include "delaunay/delaunay.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"
#include "quant/scalar_quantizer.hpp"
#include "reconstruct/reconstruct.hpp"
#include "encoder/tuning.hpp"
#include "encoder/distance.hpp"
#include "encoder/winding.hpp"
#include "util/kdtree.hpp"

using namespace hmc;
using namespace hmc::detail;

namespace {

const char* fidelity_name(Fidelity f) {
  switch (f) {
    case Fidelity::rule: return "rule";
    case Fidelity::topology: return "topology";
    case Fidelity::exact: return "exact";
    default: return "shape";
  }
}

using Face = std::array<std::uint32_t, 3>;
double pct(std::size_t a, std::size_t b) { return 100.0 * static_cast<double>(a) / static_cast<double>(std::max<std::size_t>(b, 1)); }
Face sorted3(Face f) {
  std::sort(f.begin(), f.end());
  return f;
}
Tetrahedron sorted4(Tetrahedron t) {
  std::sort(t.begin(), t.end());
  return t;
}

// One-sided max distance from surface A (sampled) to surface B.
double one_sided(const std::vector<Vec3>& p, const std::vector<Face>& a, const SurfaceDistance& to_b) {
  double worst = 0;
  const double w[7][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {.5, .5, 0}, {0, .5, .5}, {.5, 0, .5}, {1. / 3, 1. / 3, 1. / 3}};
  for (const auto& f : a)
    for (const auto& bc : w) {
      Vec3 q{0, 0, 0};
      for (int i = 0; i < 3; ++i)
        for (int ax = 0; ax < 3; ++ax) q[ax] += bc[i] * p[f[i]][ax];
      worst = std::max(worst, to_b(q));
    }
  return worst;
}

struct Topology {
  std::size_t border_edges = 0, nonmanifold_edges = 0, components = 0;
  long euler = 0;
};

Topology topology(const std::vector<Face>& tris) {
  Topology t;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edges;
  std::set<std::uint32_t> verts;
  for (std::uint32_t i = 0; i < tris.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const auto a = std::min(tris[i][k], tris[i][(k + 1) % 3]), b = std::max(tris[i][k], tris[i][(k + 1) % 3]);
      edges[{a, b}].push_back(i);
      verts.insert(tris[i][k]);
    }
  std::vector<std::uint32_t> parent(tris.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& [e, fs] : edges) {
    if (fs.size() == 1) ++t.border_edges;
    if (fs.size() > 2) ++t.nonmanifold_edges;
    for (std::size_t i = 1; i < fs.size(); ++i) parent[find(fs[i])] = find(fs[0]);
  }
  for (std::uint32_t i = 0; i < tris.size(); ++i) t.components += find(i) == i;
  t.euler = static_cast<long>(verts.size()) - static_cast<long>(edges.size()) + static_cast<long>(tris.size());
  return t;
}

void topo_json(const char* key, const Topology& t) {
  std::printf("\"%s\": {\"border_edges\": %zu, \"nonmanifold_edges\": %zu, \"components\": %zu, \"euler\": %ld}", key,
              t.border_edges, t.nonmanifold_edges, t.components, t.euler);
}


double tet_volume(const std::vector<Vec3>& p, const std::vector<Tetrahedron>& ts) {
  double v = 0;
  for (const auto& t : ts) {
    const Vec3 &a = p[t[0]], &b = p[t[1]], &c = p[t[2]], &d = p[t[3]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]},
                 x[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    v += std::abs(u[0] * (w[1] * x[2] - w[2] * x[1]) - u[1] * (w[0] * x[2] - w[2] * x[0]) + u[2] * (w[0] * x[1] - w[1] * x[0])) / 6;
  }
  return v;
}

std::vector<Vec3> to_vec3(const std::vector<GridPoint>& g) {
  std::vector<Vec3> out(g.size());
  for (std::size_t i = 0; i < g.size(); ++i) out[i] = {double(g[i][0]), double(g[i][1]), double(g[i][2])};
  return out;
}

// End-to-end report on a stream: encode with the public API, decode the
// bytes, and compare the decoder's finest level with the input on the grid.
// Nothing is matched by identity (a report written for streams whose points
// need not be the input's); instead:
//  - point error: each input grid point to its nearest decoded point and
//    back (max and RMS, % of the input's box diagonal);
//  - surface Hausdorff between the rebuilt surface (a volume's boundary)
//    and the input's, both directions, sampled as in the exact report;
//  - topology of the rebuilt surface (border and non-manifold edges,
//    components, Euler characteristic) beside the input's;
//  - matched share: input triangles (tetrahedra) whose vertices' nearest
//    decoded points are distinct and form an output triangle (tetrahedron);
//    with exact layers this is the plain reproduced share (of all input
//    simplices, not of the Delaunay ceiling);
//  - whether the decoder rebuilt exactly what the encoder predicted.
int stream_report(const char* path, const Mesh& m, int q, Fidelity fidelity, int levels, bool per_level, bool fit_coarse, double preview) {
  EncodeOptions opt;
  opt.fit_coarse_levels = fit_coarse;
  opt.preview_ratio = preview;
  opt.bits = q;
  opt.fidelity = fidelity;
  opt.levels = levels;
  opt.write_info = false;
  const auto t0 = std::chrono::steady_clock::now();
  auto enc = encode(m, opt);
  if (!enc) {
    std::fprintf(stderr, "encoder: %s\n", enc.error().to_string().c_str());
    return 3;
  }
  const Encoded& e = enc.value();
  const auto t1 = std::chrono::steady_clock::now();
  auto dec = decode(e.bytes.data(), e.bytes.size());
  if (!dec) {
    std::fprintf(stderr, "the decoder rejects the encoder's stream: %s\n", dec.error().to_string().c_str());
    return 3;
  }
  const auto t2 = std::chrono::steady_clock::now();
  const DecodedLevel& fin = dec.value().finest();
  const Kind kind = e.report.kind;
  const bool same = fin.points == e.points && fin.triangles == e.triangles && fin.tetrahedra == e.tetrahedra;

  // The input on the grid (the encoder's quantizer), duplicates merged.
  const auto g = quantize(m.points, e.report.quantizer);
  std::vector<GridPoint> in_pts(g);
  std::sort(in_pts.begin(), in_pts.end());
  in_pts.erase(std::unique(in_pts.begin(), in_pts.end()), in_pts.end());
  std::vector<std::uint32_t> idx(g.size());
  for (std::size_t i = 0; i < g.size(); ++i)
    idx[i] = static_cast<std::uint32_t>(std::lower_bound(in_pts.begin(), in_pts.end(), g[i]) - in_pts.begin());
  std::vector<Face> in_tris;
  std::vector<Tetrahedron> in_tets;
  for (const auto& t : m.triangles) {
    Face f{idx[t[0]], idx[t[1]], idx[t[2]]};
    if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) in_tris.push_back(f);
  }
  for (const auto& t : m.tetrahedra) {
    Tetrahedron f{idx[t[0]], idx[t[1]], idx[t[2]], idx[t[3]]};
    auto s = sorted4(f);
    if (s[0] != s[1] && s[1] != s[2] && s[2] != s[3]) in_tets.push_back(f);
  }
  const std::vector<Vec3> in_gp = to_vec3(in_pts), out_gp = to_vec3(fin.points);
  double diag = 0;
  for (int a = 0; a < 3; ++a) {
    double lo = 1e300, hi = -1e300;
    for (const auto& p : in_gp) lo = std::min(lo, p[a]), hi = std::max(hi, p[a]);
    diag += (hi - lo) * (hi - lo);
  }
  diag = std::sqrt(diag);

  // Point error, and each input point's nearest decoded point.
  using Tree = KdTree<std::int64_t>;
  auto ipts = [](const std::vector<GridPoint>& v) {
    std::vector<Tree::Point> o(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) o[i] = {std::int64_t(v[i][0]), std::int64_t(v[i][1]), std::int64_t(v[i][2])};
    return o;
  };
  const auto in_i = ipts(in_pts), out_i = ipts(fin.points);
  const Tree out_tree(out_i), in_tree(in_i);
  std::vector<std::uint32_t> near(in_pts.size());
  double in_out_max = 0, in_out_sum = 0, out_in_max = 0, out_in_sum = 0;
  std::size_t moved = 0;
  for (std::size_t i = 0; i < in_i.size(); ++i) {
    const auto h = out_tree.nearest(in_i[i]);
    near[i] = h.index;
    moved += h.d2 != 0;
    in_out_max = std::max(in_out_max, double(h.d2));
    in_out_sum += double(h.d2);
  }
  for (const auto& p : out_i) {
    const auto h = in_tree.nearest(p);
    out_in_max = std::max(out_in_max, double(h.d2));
    out_in_sum += double(h.d2);
  }
  const double pt_haus = std::sqrt(std::max(in_out_max, out_in_max));
  const double pt_rms = std::sqrt(std::max(in_out_sum / double(in_i.size()), out_in_sum / double(std::max<std::size_t>(out_i.size(), 1))));

  std::printf("{\"model\": \"%s\", \"mode\": \"stream\", \"kind\": \"%s\", \"fidelity\": \"%s\", \"q\": %d, "
              "\"levels\": %zu, \"bytes\": %zu, "
              "\"input_vertices\": %zu, \"bits_per_input_vertex\": %.3f, \"points_in\": %zu, \"points_out\": %zu, "
              "\"points_moved\": %zu, \"decoder_matches_encoder\": %s, ",
              path, kind_name(kind), fidelity_name(fidelity),
              q, dec.value().levels.size(), e.bytes.size(), m.points.size(),
              8.0 * double(e.bytes.size()) / double(m.points.size()), in_pts.size(), fin.points.size(),
              moved,
              same ? "true" : "false");
  std::printf("\"point_hausdorff_pct_diag\": %.4f, \"point_rms_pct_diag\": %.5f, ", 100 * pt_haus / diag,
              100 * pt_rms / diag);
  auto secs = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
  std::printf("\"seconds\": {\"encode\": %.3f, \"decode\": %.3f}, ", secs(t0, t1), secs(t1, t2));

  // Matched share: input simplices carried by the nearest-point map onto output simplices.
  auto carried = [&](auto simplex) {
    for (auto& v : simplex) v = near[v];
    return simplex;
  };
  if (kind == Kind::surface) {
    std::set<Face> out;
    for (const auto& f : fin.triangles) out.insert(sorted3(f));
    std::size_t matched = 0;
    for (const auto& f : in_tris) matched += out.count(sorted3(carried(f)));
    std::vector<Face> outv(fin.triangles.begin(), fin.triangles.end());
    SurfaceDistance to_in(in_gp, in_tris), to_out(out_gp, outv);
    const double h_out = one_sided(out_gp, outv, to_in), h_in = one_sided(in_gp, in_tris, to_out);
    std::printf("\"input_triangles\": %zu, \"output_triangles\": %zu, \"matched\": %zu, \"matched_pct\": %.2f, "
                "\"hausdorff_out_to_in_pct\": %.4f, \"hausdorff_in_to_out_pct\": %.4f, \"hausdorff_pct_diag\": %.4f, ",
                in_tris.size(), outv.size(), matched, pct(matched, in_tris.size()), 100 * h_out / diag,
                100 * h_in / diag, 100 * std::max(h_out, h_in) / diag);
    topo_json("input_topology", topology(in_tris));
    std::printf(", ");
    topo_json("output_topology", topology(outv));
  } else {
    std::set<Tetrahedron> out;
    for (const auto& t : fin.tetrahedra) out.insert(sorted4(t));
    std::size_t matched = 0;
    for (const auto& t : in_tets) matched += out.count(sorted4(carried(t)));
    std::vector<Tetrahedron> outv(fin.tetrahedra.begin(), fin.tetrahedra.end());
    const auto in_bd = boundary_faces(in_gp, in_tets), out_bd = boundary_faces(out_gp, outv);
    SurfaceDistance to_in(in_gp, in_bd), to_out(out_gp, out_bd);
    const double h_out = one_sided(out_gp, out_bd, to_in), h_in = one_sided(in_gp, in_bd, to_out);
    // A volume file may also carry triangles (MEDIT's Triangles section): say so.
    std::printf("\"input_file_triangles\": %zu, ", m.triangles.size());
    std::printf("\"input_tets\": %zu, \"output_tets\": %zu, \"matched\": %zu, \"matched_pct\": %.2f, "
                "\"volume_ratio\": %.5f, \"boundary_hausdorff_out_to_in_pct\": %.4f, "
                "\"boundary_hausdorff_in_to_out_pct\": %.4f, \"boundary_hausdorff_pct_diag\": %.4f, ",
                in_tets.size(), outv.size(), matched, pct(matched, in_tets.size()),
                tet_volume(out_gp, outv) / tet_volume(in_gp, in_tets), 100 * h_out / diag, 100 * h_in / diag,
                100 * std::max(h_out, h_in) / diag);
    topo_json("input_boundary_topology", topology(in_bd));
    std::printf(", ");
    topo_json("output_boundary_topology", topology(out_bd));
  }
  if (per_level) {
    // Every decoded level against the input surface (a volume's boundary):
    // symmetric Hausdorff, sampled as above, and the level's topology.
    const std::vector<Face> in_surface = kind == Kind::surface ? in_tris : boundary_faces(in_gp, in_tets);
    const SurfaceDistance to_in(in_gp, in_surface);
    std::printf(", \"per_level\": [");
    const auto& dl = dec.value().levels;
    for (std::size_t i = 0; i < dl.size(); ++i) {
      const int lod = static_cast<int>(dl.size() - 1 - i);
      const LevelReport* lr = nullptr;
      for (const auto& l : e.report.levels)
        if (l.lod == lod) lr = &l;
      const std::vector<Vec3> lp = to_vec3(dl[i].points);
      std::vector<Face> surf;
      if (kind == Kind::surface)
        surf.assign(dl[i].triangles.begin(), dl[i].triangles.end());
      else
        surf = boundary_faces(lp, std::vector<Tetrahedron>(dl[i].tetrahedra.begin(), dl[i].tetrahedra.end()));
      double h_out = 0, h_in = 0;
      if (!surf.empty()) {
        const SurfaceDistance to_level(lp, surf);
        h_out = one_sided(lp, surf, to_in);
        h_in = one_sided(in_gp, in_surface, to_level);
      }
      std::printf("%s{\"lod\": %d, \"points\": %zu, \"points_pct\": %.2f, \"stream_bytes\": %llu, "
                  "\"side_bytes\": %llu, \"hausdorff_out_to_in_pct\": %.4f, \"hausdorff_in_to_out_pct\": %.4f, "
                  "\"hausdorff_pct_diag\": %.4f, ",
                  i ? ", " : "", lod, dl[i].points.size(), pct(dl[i].points.size(), in_pts.size()),
                  static_cast<unsigned long long>(lr ? lr->stream_bytes : 0),
                  static_cast<unsigned long long>(lr ? lr->side_bytes : 0), 100 * h_out / diag, 100 * h_in / diag,
                  surf.empty() ? 100.0 : 100 * std::max(h_out, h_in) / diag);
      topo_json("topology", topology(surf));
      std::printf("}");
    }
    std::printf("]");
  }
  std::printf("}\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: fidelity MODEL [--bits Q] [--fidelity rule|topology|shape|exact] [--levels L] "
                         "[--per-level] [--fit-coarse] [--preview-ratio R]\n");
    return 1;
  }
  int q = 12, levels = 0;
  bool per_level = false, fit_coarse = false;
  double preview = 0;
  Fidelity fidelity = Fidelity::shape;
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--bits") && i + 1 < argc) q = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--levels") && i + 1 < argc) levels = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--per-level")) per_level = true;
    if (!std::strcmp(argv[i], "--fit-coarse")) fit_coarse = true;
    if (!std::strcmp(argv[i], "--preview-ratio") && i + 1 < argc) preview = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--fidelity") && i + 1 < argc) {
      const std::string f = argv[++i];
      fidelity = f == "rule" ? Fidelity::rule : f == "exact" ? Fidelity::exact : f == "topology" ? Fidelity::topology : Fidelity::shape;
    }
  }
  auto mesh = io::read_mesh(argv[1]);
  if (!mesh) {
    std::fprintf(stderr, "%s\n", mesh.error().to_string().c_str());
    return 2;
  }
  const Mesh& m = mesh.value();
  if (levels > 0) return stream_report(argv[1], m, q, fidelity, levels, per_level, fit_coarse, preview);
  const Kind kind = m.tetrahedra.empty() ? Kind::surface : Kind::volume;
  const auto sq = fit_quantizer(m.points, q);
  const auto g = quantize(m.points, sq);
  std::vector<GridPoint> pts(g);
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  std::vector<std::uint32_t> idx(g.size());
  for (std::size_t i = 0; i < g.size(); ++i)
    idx[i] = static_cast<std::uint32_t>(std::lower_bound(pts.begin(), pts.end(), g[i]) - pts.begin());
  std::vector<Vec3> gp(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) gp[i] = {double(pts[i][0]), double(pts[i][1]), double(pts[i][2])};

  // The input on the grid.
  std::vector<Face> in_tris;
  std::vector<Tetrahedron> in_tets;
  for (const auto& t : m.triangles) {
    Face f{idx[t[0]], idx[t[1]], idx[t[2]]};
    if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) in_tris.push_back(f);
  }
  for (const auto& t : m.tetrahedra) {
    Tetrahedron f{idx[t[0]], idx[t[1]], idx[t[2]], idx[t[3]]};
    auto s = sorted4(f);
    if (s[0] != s[1] && s[1] != s[2] && s[2] != s[3]) in_tets.push_back(f);
  }
  // The surface the encoder aims at (input_on_grid): a volume's boundary
  // turned by its tetrahedra's orientation in the input's own coordinates,
  // or the triangles made to agree in orientation.
  const std::vector<Face> surface = input_on_grid(m, g, pts).surface;

  const auto t0 = std::chrono::steady_clock::now();
  const auto dt = delaunay(pts);
  const auto t1 = std::chrono::steady_clock::now();
  double unsure = 0;
  const auto truth = truth_labels(pts, dt, gp, surface, surface, nullptr, false, &unsure);
  const auto t2 = std::chrono::steady_clock::now();
  // Border vertices of an open input surface.
  std::vector<std::uint32_t> border;
  if (kind == Kind::surface) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> ec;
    for (const auto& f : in_tris)
      for (int k = 0; k < 3; ++k) ++ec[{std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])}];
    for (const auto& [e, c] : ec)
      if (c == 1) border.push_back(e.first), border.push_back(e.second);
    std::sort(border.begin(), border.end());
    border.erase(std::unique(border.begin(), border.end()), border.end());
  }
  TuningReport rep;
  TuneInput ti;
  ti.truth = truth;
  ti.border = border;
  ti.surface_points = &gp;
  ti.surface = &surface;
  if ((fidelity == Fidelity::shape || fidelity == Fidelity::topology) &&
      (kind == Kind::volume || border.empty())) {  // as the encoder does
    ti.clean_target = true;
    {
      const auto t = topology(in_tris);
      ti.target_components = t.components;
      ti.target_euler = t.euler;
    }
  }
  auto params = tune(pts, dt, kind, ti, fidelity, &rep);
  if (kind == Kind::surface && !border.empty() && unsure > kSheetUnsure) {  // as the encoder does
    TuneInput sheet = ti;
    sheet.truth = truth_labels(pts, dt, gp, surface, surface, nullptr, true);
    TuningReport sheet_rep;
    auto sheet_params = tune(pts, dt, kind, sheet, fidelity, &sheet_rep);
    if (write_recon(sheet_params).size() < write_recon(params).size()) {
      params = std::move(sheet_params);
      rep = std::move(sheet_rep);
    }
  }
  const auto t3 = std::chrono::steady_clock::now();
  const auto rec = reconstruct(pts, dt, kind, params);
  const auto t4 = std::chrono::steady_clock::now();

  // Delaunay faces and tets, for the ceiling.
  std::set<Face> dt_faces;
  std::set<Tetrahedron> dt_tets;
  for (const auto& t : dt.tets) {
    dt_tets.insert(sorted4(t));
    for (int k = 0; k < 4; ++k) dt_faces.insert(sorted3({t[kFaceVertices[k][0]], t[kFaceVertices[k][1]], t[kFaceVertices[k][2]]}));
  }
  auto secs = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
  double diag = 0;
  for (int a = 0; a < 3; ++a) {
    double lo = 1e300, hi = -1e300;
    for (const auto& p : gp) lo = std::min(lo, p[a]), hi = std::max(hi, p[a]);
    diag += (hi - lo) * (hi - lo);
  }
  diag = std::sqrt(diag);

  std::printf("{\"model\": \"%s\", \"kind\": \"%s\", \"fidelity\": \"%s\", \"points\": %zu, \"dt_tets\": %zu, ", argv[1],
              kind_name(kind), fidelity_name(fidelity),
              pts.size(), dt.tets.size());
  const std::size_t rcon_bytes = write_recon(params).size() + kChunkOverhead;
  std::printf("\"filters\": [%u, %u, %u, %u, %u, %u], ", params.filters[0], params.filters[1], params.filters[2],
              params.filters[3], params.filters[4], params.filters[5]);
  std::printf("\"classes\": %zu, \"scale_rank\": %u, \"peel\": %s, \"toggles\": %zu, \"mismatches\": %llu, "
              "\"rcon_bytes\": %zu, \"rcon_bits_per_point\": %.3f, ",
              params.multipliers.size(), params.scale_rank, params.peel ? "true" : "false", toggle_count(params),
              static_cast<unsigned long long>(rep.mismatches_before_toggles), rcon_bytes,
              8.0 * static_cast<double>(rcon_bytes) / static_cast<double>(pts.size()));
  std::printf("\"seconds\": {\"delaunay\": %.3f, \"truth\": %.3f, \"tune\": %.3f, \"reconstruct\": %.3f}, ", secs(t0, t1),
              secs(t1, t2), secs(t2, t3), secs(t3, t4));
  if (kind == Kind::surface) {
    std::set<Face> out;
    for (const auto& f : rec.triangles) out.insert(sorted3(f));
    std::set<Face> in;
    for (const auto& f : in_tris) in.insert(sorted3(f));
    std::size_t in_dt = 0, reproduced = 0, extra = 0;
    for (const auto& f : in) {
      in_dt += dt_faces.count(f);
      reproduced += out.count(f);
    }
    for (const auto& f : out) extra += !in.count(f);
    std::vector<Face> outv(rec.triangles.begin(), rec.triangles.end());
    SurfaceDistance to_in(gp, in_tris), to_out(gp, outv);
    const double h_out = one_sided(gp, outv, to_in), h_in = one_sided(gp, in_tris, to_out);
    const double h = std::max(h_out, h_in);
    std::printf("\"hausdorff_out_to_in_pct\": %.4f, \"hausdorff_in_to_out_pct\": %.4f, ", 100 * h_out / diag,
                100 * h_in / diag);
    std::printf("\"input_triangles\": %zu, \"in_delaunay\": %zu, \"ceiling_pct\": %.2f, \"reproduced\": %zu, "
                "\"reproduced_pct_of_ceiling\": %.2f, \"output_triangles\": %zu, \"extra\": %zu, \"hausdorff_pct_diag\": %.4f, ",
                in.size(), in_dt, pct(in_dt, in.size()), reproduced, pct(reproduced, in_dt),
                out.size(), extra, 100.0 * h / diag);
    topo_json("input_topology", topology(in_tris));
    std::printf(", ");
    topo_json("output_topology", topology(outv));
  } else {
    std::set<Tetrahedron> out, in;
    for (const auto& t : rec.tetrahedra) out.insert(sorted4(t));
    for (const auto& t : in_tets) in.insert(sorted4(t));
    std::size_t in_dt = 0, reproduced = 0, extra = 0;
    for (const auto& t : in) {
      in_dt += dt_tets.count(t);
      reproduced += out.count(t);
    }
    for (const auto& t : out) extra += !in.count(t);
    std::vector<Tetrahedron> outv(rec.tetrahedra.begin(), rec.tetrahedra.end());
    auto volume = [&](const std::vector<Tetrahedron>& ts) {
      double v = 0;
      for (const auto& t : ts) {
        const Vec3 &a = gp[t[0]], &b = gp[t[1]], &c = gp[t[2]], &d = gp[t[3]];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]},
                     x[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        v += std::abs(u[0] * (w[1] * x[2] - w[2] * x[1]) - u[1] * (w[0] * x[2] - w[2] * x[0]) + u[2] * (w[0] * x[1] - w[1] * x[0])) / 6;
      }
      return v;
    };
    const auto out_bd = boundary_faces(gp, outv);
    std::set<std::uint32_t> out_bv, in_bv;
    for (const auto& f : out_bd) out_bv.insert(f.begin(), f.end());
    for (const auto& f : surface) in_bv.insert(f.begin(), f.end());
    std::size_t missing_bv = 0;
    for (auto v : in_bv) missing_bv += !out_bv.count(v);
    SurfaceDistance to_in(gp, surface), to_out(gp, out_bd);
    const double h = std::max(one_sided(gp, out_bd, to_in), one_sided(gp, surface, to_out));
    std::printf("\"input_tets\": %zu, \"in_delaunay\": %zu, \"ceiling_pct\": %.2f, \"reproduced\": %zu, "
                "\"reproduced_pct_of_ceiling\": %.2f, \"output_tets\": %zu, \"extra\": %zu, \"volume_ratio\": %.5f, "
                "\"boundary_vertices\": %zu, \"boundary_vertices_missing\": %zu, \"boundary_hausdorff_pct_diag\": %.4f, ",
                in.size(), in_dt, pct(in_dt, in.size()), reproduced, pct(reproduced, in_dt),
                out.size(), extra, volume(outv) / volume(in_tets), in_bv.size(), missing_bv, 100.0 * h / diag);
    topo_json("input_boundary_topology", topology(surface));
    std::printf(", ");
    topo_json("output_boundary_topology", topology(out_bd));
  }
  std::printf("}\n");
  return 0;
}
