// SPDX-License-Identifier: AGPL-3.0-or-later
// `hmc analyze`: the thesis' per-level tables (4.1–4.12) for a mesh (encoded
// here with the given options, and for volumes once per optimiser) or for a
// stream (its decoded levels).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "cli.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"
#include "hmc/quality.hpp"

namespace hmc::cli {

void quality_json(Json& j, const quality::MeshQuality& q);

namespace {

struct EdgeStats {
  double global_alpha = 0;        // mean edge length (input units)
  double min_edge_ratio = 0;      // min over triangles of Lmin/Lmax
  double neighbour_max_ratio = 0; // min over adjacent triangle pairs of the ratio of their longest edges
  double neighbour_ratio_ratio = 0;  // same for their Lmin/Lmax ratios
  std::vector<std::pair<double, std::uint64_t>> mec;  // class centre (max incident edge), members
};

double len(const Vec3& a, const Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// Deterministic 1D clustering of values into at most `k` classes: start from
// quantile centres, then Lloyd iterations (values sorted, so each class is a
// contiguous run).
std::vector<std::pair<double, std::uint64_t>> cluster(std::vector<double> v, int k) {
  std::vector<std::pair<double, std::uint64_t>> out;
  if (v.empty()) return out;
  std::sort(v.begin(), v.end());
  std::vector<double> c;
  for (int i = 0; i < k; ++i) {
    const double x = v[std::min(v.size() - 1, (v.size() * static_cast<std::size_t>(2 * i + 1)) / static_cast<std::size_t>(2 * k))];
    if (c.empty() || x > c.back()) c.push_back(x);
  }
  std::vector<std::size_t> start(c.size() + 1);
  for (int it = 0; it < 50; ++it) {
    // Boundaries at midpoints between consecutive centres.
    start[0] = 0;
    for (std::size_t j = 1; j < c.size(); ++j)
      start[j] = static_cast<std::size_t>(std::lower_bound(v.begin(), v.end(), 0.5 * (c[j - 1] + c[j])) - v.begin());
    start[c.size()] = v.size();
    bool moved = false;
    for (std::size_t j = 0; j < c.size(); ++j) {
      if (start[j + 1] <= start[j]) continue;
      double s = 0;
      for (std::size_t i = start[j]; i < start[j + 1]; ++i) s += v[i];
      const double m = s / static_cast<double>(start[j + 1] - start[j]);
      moved |= m != c[j];
      c[j] = m;
    }
    if (!moved) break;
  }
  for (std::size_t j = 0; j < c.size(); ++j)
    if (start[j + 1] > start[j]) out.emplace_back(c[j], start[j + 1] - start[j]);
  return out;
}

EdgeStats edge_stats(const Mesh& m, int classes) {
  EdgeStats s;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edges;
  auto add_edge = [&](std::uint32_t a, std::uint32_t b, std::uint32_t owner) {
    edges[{std::min(a, b), std::max(a, b)}].push_back(owner);
  };
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) add_edge(m.triangles[t][k], m.triangles[t][(k + 1) % 3], t);
  for (std::uint32_t t = 0; t < m.tetrahedra.size(); ++t)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) add_edge(m.tetrahedra[t][i], m.tetrahedra[t][j], ~0u);
  std::vector<double> max_incident(m.points.size(), 0);
  double sum = 0;
  for (const auto& [e, owners] : edges) {
    const double l = len(m.points[e.first], m.points[e.second]);
    sum += l;
    max_incident[e.first] = std::max(max_incident[e.first], l);
    max_incident[e.second] = std::max(max_incident[e.second], l);
  }
  s.global_alpha = edges.empty() ? 0 : sum / static_cast<double>(edges.size());
  std::vector<double> lmax(m.triangles.size()), ratio(m.triangles.size());
  s.min_edge_ratio = m.triangles.empty() ? 0 : 1;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& f = m.triangles[t];
    const double a = len(m.points[f[0]], m.points[f[1]]), b = len(m.points[f[1]], m.points[f[2]]),
                 c = len(m.points[f[2]], m.points[f[0]]);
    lmax[t] = std::max({a, b, c});
    ratio[t] = lmax[t] > 0 ? std::min({a, b, c}) / lmax[t] : 0;
    s.min_edge_ratio = std::min(s.min_edge_ratio, ratio[t]);
  }
  auto rel = [](double x, double y) { return std::max(x, y) > 0 ? std::min(x, y) / std::max(x, y) : 1.0; };
  s.neighbour_max_ratio = s.neighbour_ratio_ratio = m.triangles.empty() ? 0 : 1;
  for (const auto& [e, owners] : edges)
    for (std::size_t i = 0; i < owners.size(); ++i)
      for (std::size_t j = i + 1; j < owners.size(); ++j) {
        if (owners[i] == ~0u || owners[j] == ~0u) continue;
        s.neighbour_max_ratio = std::min(s.neighbour_max_ratio, rel(lmax[owners[i]], lmax[owners[j]]));
        s.neighbour_ratio_ratio = std::min(s.neighbour_ratio_ratio, rel(ratio[owners[i]], ratio[owners[j]]));
      }
  std::vector<double> used;
  for (double x : max_incident)
    if (x > 0) used.push_back(x);
  s.mec = cluster(used, classes);
  return s;
}

Mesh level_mesh(const ScalarQuantizer& q, const DecodedLevel& l) {
  Mesh m;
  for (const auto& p : l.points) m.points.push_back(q.dequantize(p));
  m.triangles = l.triangles;
  m.tetrahedra = l.tetrahedra;
  return m;
}

struct Table {
  Kind kind;
  ScalarQuantizer q;
  std::vector<DecodedLevel> levels;   // coarsest first
  std::vector<LevelReport> reports;   // empty for streams
  std::uint64_t bytes = 0;
};

void print_surface(const Table& t, int classes, Json* j) {
  if (j) j->key("levels").begin_array();
  else
    std::printf("%-7s %8s %10s %8s %8s %12s %12s %14s\n", "level", "NV", "GA", "QT1", "QT2", "min/max e.r.",
                "N.max e.r.", "N.min/max e.r.");
  std::vector<EdgeStats> all;
  for (auto it = t.levels.rbegin(); it != t.levels.rend(); ++it) {
    const Mesh m = level_mesh(t.q, *it);
    const auto qual = quality::evaluate(m);
    const auto es = edge_stats(m, classes);
    all.push_back(es);
    if (j) {
      j->begin_object();
      j->key("level").value(it->lod).key("nv").value(static_cast<std::uint64_t>(m.points.size()));
      j->key("triangles").value(static_cast<std::uint64_t>(m.triangles.size()));
      j->key("ga").value(es.global_alpha);
      quality_json(*j, qual);
      j->key("min_edge_ratio").value(es.min_edge_ratio).key("neighbour_max_edge_ratio").value(es.neighbour_max_ratio);
      j->key("neighbour_min_max_edge_ratio").value(es.neighbour_ratio_ratio);
      j->key("mec").begin_array();
      for (const auto& [c, n] : es.mec) j->begin_object().key("value").value(c).key("members").value(n).end_object();
      j->end_array().end_object();
    } else {
      // Thesis columns: QT1 = min/max edge ratio test, QT2 = angle test (mesh means).
      std::printf("Level %-2d %8zu %10.6f %8.4f %8.4f %12.6f %12.6f %14.6f\n", it->lod, m.points.size(), es.global_alpha,
                  qual.tri_edge.mean, qual.tri_angle.mean, es.min_edge_ratio, es.neighbour_max_ratio,
                  es.neighbour_ratio_ratio);
    }
  }
  if (j) {
    j->end_array();
    return;
  }
  std::printf("\nMEC: classes of each vertex's maximum incident edge length (value, member count), per level\n");
  std::size_t rows = 0;
  for (const auto& es : all) rows = std::max(rows, es.mec.size());
  std::printf("%4s", "MEC");
  for (std::size_t l = 0; l < all.size(); ++l) std::printf(" %12s %6s", ("L" + std::to_string(l) + " value").c_str(), "MC");
  std::printf("\n");
  for (std::size_t r = 0; r < rows; ++r) {
    std::printf("%4zu", r + 1);
    for (const auto& es : all) {
      if (r < es.mec.size())
        std::printf(" %12.6f %6llu", es.mec[r].first, static_cast<unsigned long long>(es.mec[r].second));
      else
        std::printf(" %12s %6s", "----", "----");
    }
    std::printf("\n");
  }
}

void print_volume_rows(const Table& t, const char* label, Json* j) {
  for (auto it = t.levels.rbegin(); it != t.levels.rend(); ++it) {
    const Mesh m = level_mesh(t.q, *it);
    const auto qual = quality::evaluate(m);
    const LevelReport* r = nullptr;
    for (const auto& x : t.reports)
      if (x.lod == it->lod) r = &x;
    if (j) {
      j->begin_object();
      j->key("optimizer").value(label).key("level").value(it->lod);
      j->key("vn").value(static_cast<std::uint64_t>(m.points.size())).key("cn").value(static_cast<std::uint64_t>(m.tetrahedra.size()));
      j->key("layers").begin_array();
      if (r)
        for (auto n : r->layer_sizes) j->value(n);
      j->end_array();
      quality_json(*j, qual);
      j->end_object();
      continue;
    }
    std::printf("%-9s L%-2d %8zu %8zu  %7.4f %7.4f %7.4f %7.4f  ", label, it->lod, m.points.size(), m.tetrahedra.size(),
                qual.qt1.mean, qual.qt2.mean, qual.qt3.mean, qual.qt4.mean);
    if (r)
      for (auto n : r->layer_sizes) std::printf(" %6llu", static_cast<unsigned long long>(n));
    std::printf("\n");
  }
}

}  // namespace

int cmd_analyze(int argc, char** argv) {
  Args a(argc, argv, 2, {"--json"}, {"--bits", "--levels", "--ratio", "--classes"});
  const int bits = static_cast<int>(a.get_int("--bits", 12, 1, 21));
  const int levels = static_cast<int>(a.get_int("--levels", 4, 1, 64));
  const int classes = static_cast<int>(a.get_int("--classes", 16, 1, 64));
  double ratio = 0.3;
  if (a.has("--ratio")) ratio = std::strtod(a.get("--ratio").c_str(), nullptr);
  if (!a.ok() || a.positional().size() != 1 || !(ratio > 0 && ratio <= 1)) {
    std::fprintf(stderr, "hmc analyze: %s\nusage: hmc analyze IN [--levels N] [--ratio R] [--bits Q] [--json]\n",
                 a.ok() ? "need one input (mesh or .hmc stream)" : a.error().c_str());
    return kUsage;
  }
  const std::string in = a.positional()[0];
  std::vector<std::pair<std::string, Table>> tables;
  const bool is_stream = in.size() > 4 && in.substr(in.size() - 4) == ".hmc";
  if (is_stream) {
    auto bytes = io::read_file(in);
    if (!bytes) return report("cannot read " + in, bytes.error(), Stage::input);
    auto d = decode(reinterpret_cast<const std::uint8_t*>(bytes.value().data()), bytes.value().size());
    if (!d) return report(in, d.error(), Stage::input);
    tables.emplace_back("stream", Table{d.value().kind, d.value().quantizer, d.value().levels, {}, bytes.value().size()});
  } else {
    auto mesh = io::read_mesh(in);
    if (!mesh) return report("cannot read " + in, mesh.error(), Stage::input);
    const bool volume = !mesh.value().tetrahedra.empty();
    const std::vector<Optimizer> opts =
        volume ? std::vector<Optimizer>{Optimizer::forward, Optimizer::backward, Optimizer::greedy}
               : std::vector<Optimizer>{Optimizer::best};
    for (Optimizer o : opts) {
      EncodeOptions eo;
      eo.bits = bits;
      eo.levels = levels;
      eo.removal_ratio = ratio;
      eo.optimizer = o;
      auto e = encode(mesh.value(), eo);
      if (!e) return report("cannot encode " + in, e.error(), Stage::input);
      tables.emplace_back(optimizer_name(o), Table{e.value().report.kind, e.value().report.quantizer, e.value().levels,
                                                   e.value().report.levels, e.value().bytes.size()});
    }
  }
  Json j;
  Json* jp = a.flag("--json") ? &j : nullptr;
  if (jp) j.begin_object().key("input").value(in).key("kind").value(kind_name(tables.front().second.kind));
  else
    std::printf("%s: %s, q = %d, %zu level(s)\n\n", in.c_str(), kind_name(tables.front().second.kind),
                tables.front().second.q.bits, tables.front().second.levels.size());
  if (tables.front().second.kind == Kind::volume) {
    if (jp) j.key("levels").begin_array();
    else
      std::printf("%-9s %-3s %8s %8s  %7s %7s %7s %7s   layers L0 L1 ...\n", "optimizer", "lvl", "VN", "CN", "QT1", "QT2",
                  "QT3", "QT4");
    for (const auto& [label, t] : tables) print_volume_rows(t, label.c_str(), jp);
    if (jp) j.end_array();
  } else {
    print_surface(tables.front().second, classes, jp);
  }
  if (jp) {
    j.end_object();
    std::fputs(j.str().c_str(), stdout);
  }
  return kOk;
}

}  // namespace hmc::cli
