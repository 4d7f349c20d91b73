// SPDX-License-Identifier: AGPL-3.0-or-later
// `hmc analyze`: the thesis' per-level tables (4.1–4.12) for a mesh (encoded
// here with the given options, and for volumes once per optimiser) or for a
// stream (its decoded levels).
//
// Everything is measured on the decoded levels (points and rebuilt simplices),
// so a mesh and the stream made from it with the same options give the same
// rows. JSON: a value that is not defined for a level (a triangle test on a
// mesh with no triangles, a ratio over no pair of neighbouring triangles, the
// optimiser of a stream's level) is null, never 0.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "cli.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"
#include "hmc/quality.hpp"

namespace hmc::cli {

namespace {

constexpr double kUndefined = std::numeric_limits<double>::quiet_NaN();  // written as null
constexpr std::uint32_t kNone = 0xFFFFFFFFu;
constexpr double kPi = 3.14159265358979323846;
constexpr double kSolidAngleTolerance = 1e-9;  // as the encoder's classification (hierarchy.hpp)

struct EdgeStats {
  std::uint64_t edges = 0;                  // distinct edges of the triangles or tetrahedra
  double global_alpha = kUndefined;         // mean edge length (input units)
  double min_edge_ratio = kUndefined;       // min over triangles of Lmin/Lmax
  double neighbour_max_ratio = kUndefined;  // min over adjacent triangle pairs of the ratio of their longest edges
  double neighbour_ratio_ratio = kUndefined;  // same for their Lmin/Lmax ratios
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

struct EdgeUse {
  std::uint32_t a, b, owner;  // a < b; owner: the triangle, or kNone for a tetrahedron's edge
  bool operator<(const EdgeUse& o) const {
    return a != o.a ? a < o.a : b != o.b ? b < o.b : owner < o.owner;
  }
};

EdgeStats edge_stats(const Mesh& m, int classes) {
  EdgeStats s;
  const std::size_t n = m.points.size();
  std::vector<EdgeUse> uses;
  uses.reserve(3 * m.triangles.size() + 6 * m.tetrahedra.size());
  auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t owner) {
    if (a != b && a < n && b < n) uses.push_back({std::min(a, b), std::max(a, b), owner});
  };
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) add(m.triangles[t][k], m.triangles[t][(k + 1) % 3], t);
  for (const auto& t : m.tetrahedra)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) add(t[i], t[j], kNone);
  std::sort(uses.begin(), uses.end());
  std::vector<double> max_incident(n, 0);
  double sum = 0;
  // Triangle tests.
  std::vector<double> lmax(m.triangles.size(), 0), ratio(m.triangles.size(), 0);
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& f = m.triangles[t];
    if (f[0] >= n || f[1] >= n || f[2] >= n) continue;
    const double a = len(m.points[f[0]], m.points[f[1]]), b = len(m.points[f[1]], m.points[f[2]]),
                 c = len(m.points[f[2]], m.points[f[0]]);
    lmax[t] = std::max({a, b, c});
    ratio[t] = lmax[t] > 0 ? std::min({a, b, c}) / lmax[t] : 0;
    s.min_edge_ratio = std::isnan(s.min_edge_ratio) ? ratio[t] : std::min(s.min_edge_ratio, ratio[t]);
  }
  auto rel = [](double x, double y) { return std::max(x, y) > 0 ? std::min(x, y) / std::max(x, y) : 1.0; };
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].a == uses[i].a && uses[j].b == uses[i].b) ++j;
    const double l = len(m.points[uses[i].a], m.points[uses[i].b]);
    ++s.edges;
    sum += l;
    max_incident[uses[i].a] = std::max(max_incident[uses[i].a], l);
    max_incident[uses[i].b] = std::max(max_incident[uses[i].b], l);
    // Pairs of triangles sharing this edge (kNone sorts last).
    for (std::size_t x = i; x < j && uses[x].owner != kNone; ++x)
      for (std::size_t y = x + 1; y < j && uses[y].owner != kNone; ++y) {
        if (uses[y].owner == uses[x].owner) continue;
        const double r1 = rel(lmax[uses[x].owner], lmax[uses[y].owner]);
        const double r2 = rel(ratio[uses[x].owner], ratio[uses[y].owner]);
        s.neighbour_max_ratio = std::isnan(s.neighbour_max_ratio) ? r1 : std::min(s.neighbour_max_ratio, r1);
        s.neighbour_ratio_ratio = std::isnan(s.neighbour_ratio_ratio) ? r2 : std::min(s.neighbour_ratio_ratio, r2);
      }
    i = j;
  }
  if (s.edges) s.global_alpha = sum / static_cast<double>(s.edges);
  std::vector<double> used;
  for (double x : max_incident)
    if (x > 0) used.push_back(x);
  s.mec = cluster(used, classes);
  return s;
}

// Boundary / inner classification of a volume level by both methods of the
// thesis (§3.3 faces owned by one tetrahedron; §3.2 solid-angle sum below
// 4π), and its breadth-first layers from the boundary — the same rules as the
// encoder's decimation (libhmc/src/encoder/hierarchy), recomputed here so that every
// level, the coarsest too and the levels of a stream, has them.
struct VolumeLayers {
  std::vector<std::uint64_t> layers;  // L0 (boundary by faces; and points of no tetrahedron), L1, ...
  std::uint64_t boundary_by_faces = 0, boundary_by_angle = 0, disagreements = 0;
};

__extension__ typedef __int128 Int128;  // as libhmc's exact predicates

double det3(std::int64_t ux, std::int64_t uy, std::int64_t uz, std::int64_t vx, std::int64_t vy, std::int64_t vz,
            std::int64_t wx, std::int64_t wy, std::int64_t wz) {
  const Int128 d = static_cast<Int128>(ux) * (vy * wz - vz * wy) - static_cast<Int128>(uy) * (vx * wz - vz * wx) +
                     static_cast<Int128>(uz) * (vx * wy - vy * wx);
  return static_cast<double>(d);
}

VolumeLayers volume_layers(const DecodedLevel& l) {
  const auto& p = l.points;
  const std::size_t n = p.size();
  std::vector<std::array<std::uint32_t, 4>> tets;
  for (const auto& t : l.tetrahedra) {
    bool ok = t[0] < n && t[1] < n && t[2] < n && t[3] < n;
    for (int i = 0; i < 4 && ok; ++i)
      for (int j = 0; j < i; ++j) ok &= t[i] != t[j];
    if (ok) tets.push_back({t[0], t[1], t[2], t[3]});
  }
  // Faces owned by exactly one tetrahedron.
  std::vector<std::array<std::uint32_t, 3>> faces;
  faces.reserve(4 * tets.size());
  for (const auto& t : tets)
    for (int k = 0; k < 4; ++k) {
      std::array<std::uint32_t, 3> f{t[(k + 1) & 3], t[(k + 2) & 3], t[(k + 3) & 3]};
      std::sort(f.begin(), f.end());
      faces.push_back(f);
    }
  std::sort(faces.begin(), faces.end());
  std::vector<std::uint8_t> boundary(n, 0), in_tet(n, 0);
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j] == faces[i]) ++j;
    if (j == i + 1)
      for (std::uint32_t v : faces[i]) boundary[v] = 1;
    i = j;
  }
  // Solid angles (Van Oosterom–Strackee), as the encoder sums them.
  std::vector<double> angle(n, 0);
  auto norm = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    const double a = static_cast<double>(x), b = static_cast<double>(y), c = static_cast<double>(z);
    return std::sqrt(a * a + b * b + c * c);
  };
  for (const auto& t : tets) {
    auto d = [&](int i, int k) { return static_cast<std::int64_t>(p[t[i]][k]) - static_cast<std::int64_t>(p[t[0]][k]); };
    const double six_v = std::fabs(det3(d(1, 0), d(1, 1), d(1, 2), d(2, 0), d(2, 1), d(2, 2), d(3, 0), d(3, 1), d(3, 2)));
    for (int i = 0; i < 4; ++i) {
      in_tet[t[i]] = 1;
      const GridPoint& o = p[t[i]];
      std::int64_t e[3][3];
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
          e[r][k] = static_cast<std::int64_t>(p[t[(i + 1 + r) & 3]][k]) - static_cast<std::int64_t>(o[k]);
      auto dot = [&](int r, int s) { return static_cast<double>(e[r][0] * e[s][0] + e[r][1] * e[s][1] + e[r][2] * e[s][2]); };
      const double la = norm(e[0][0], e[0][1], e[0][2]), lb = norm(e[1][0], e[1][1], e[1][2]),
                   ld = norm(e[2][0], e[2][1], e[2][2]);
      const double den = la * lb * ld + dot(0, 1) * ld + dot(0, 2) * lb + dot(1, 2) * la;
      angle[t[i]] += 2.0 * std::atan2(six_v, den);
    }
  }
  VolumeLayers out;
  for (std::size_t v = 0; v < n; ++v) {
    if (!in_tet[v]) boundary[v] = 1;
    const bool by_angle = !in_tet[v] || angle[v] < 4.0 * kPi - kSolidAngleTolerance;
    out.boundary_by_faces += boundary[v];
    out.boundary_by_angle += by_angle;
    out.disagreements += boundary[v] != static_cast<std::uint8_t>(by_angle);
  }
  // Vertex graph (tetrahedron edges), then layers by breadth-first search.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> arcs;
  arcs.reserve(12 * tets.size());
  for (const auto& t : tets)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (i != j) arcs.emplace_back(t[i], t[j]);
  std::sort(arcs.begin(), arcs.end());
  arcs.erase(std::unique(arcs.begin(), arcs.end()), arcs.end());
  std::vector<std::size_t> offset(n + 1, 0);
  for (const auto& a : arcs) ++offset[a.first + 1];
  for (std::size_t v = 0; v < n; ++v) offset[v + 1] += offset[v];
  std::vector<std::uint32_t> layer(n, kNone), queue;
  for (std::uint32_t v = 0; v < n; ++v)
    if (boundary[v]) {
      layer[v] = 0;
      queue.push_back(v);
    }
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::uint32_t v = queue[head];
    for (std::size_t k = offset[v]; k < offset[v + 1]; ++k) {
      const std::uint32_t u = arcs[k].second;
      if (layer[u] == kNone) {
        layer[u] = layer[v] + 1;
        queue.push_back(u);
      }
    }
  }
  out.layers.assign(1, 0);
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t k = layer[v] == kNone ? 0 : layer[v];  // unreachable (invalid meshes only): counted in L0
    if (k >= out.layers.size()) out.layers.resize(k + 1, 0);
    ++out.layers[k];
  }
  return out;
}

Mesh level_mesh(const ScalarQuantizer& q, const DecodedLevel& l) {
  Mesh m;
  for (const auto& p : l.points) m.points.push_back(q.dequantize(p));
  m.triangles = l.triangles;
  m.tetrahedra = l.tetrahedra;
  return m;
}

double mean_or_null(const quality::Stats& s) { return s.count ? s.mean : kUndefined; }

// Quality of one level: the whole-mesh means under the keys `hmc quality`
// uses (null where the mesh has no element of that kind), details beside.
void quality_fields(Json& j, const quality::MeshQuality& q) {
  j.key("tri_angle").value(mean_or_null(q.tri_angle)).key("tri_edge").value(mean_or_null(q.tri_edge));
  j.key("qt1").value(mean_or_null(q.qt1)).key("qt2").value(mean_or_null(q.qt2));
  j.key("qt3").value(mean_or_null(q.qt3)).key("qt4").value(mean_or_null(q.qt4));
  j.key("details").begin_object();
  const std::pair<const char*, const quality::Stats*> all[] = {{"tri_angle", &q.tri_angle}, {"tri_edge", &q.tri_edge},
                                                               {"qt1", &q.qt1}, {"qt2", &q.qt2},
                                                               {"qt3", &q.qt3}, {"qt4", &q.qt4}};
  for (const auto& [name, s] : all) {
    j.key(name).begin_object();
    j.key("count").value(static_cast<std::uint64_t>(s->count));
    j.key("mean").value(mean_or_null(*s)).key("min").value(s->count ? s->min : kUndefined);
    j.key("max").value(s->count ? s->max : kUndefined);
    j.key("histogram").begin_array();
    for (auto h : s->histogram) j.value(static_cast<std::uint64_t>(h));
    j.end_array().end_object();
  }
  j.end_object();
}

void mec_json(Json& j, const EdgeStats& es) {
  j.key("mec").begin_array();
  for (const auto& [c, n] : es.mec) j.begin_object().key("value").value(c).key("members").value(n).end_object();
  j.end_array();
}

// Text cells: "-" for an undefined value.
std::string cell(double v, int width, int precision) {
  char buf[64];
  if (std::isnan(v)) std::snprintf(buf, sizeof buf, "%*s", width, "-");
  else std::snprintf(buf, sizeof buf, "%*.*f", width, precision, v);
  return buf;
}

struct Table {
  std::string optimizer;              // the requested optimiser; empty for a stream
  Kind kind = Kind::points;
  ScalarQuantizer q;
  std::vector<DecodedLevel> levels;   // coarsest first
  std::vector<LevelReport> reports;   // the encoder's, coarsest first; empty for streams
  std::uint64_t bytes = 0;
};

const LevelReport* report_of(const Table& t, int lod) {
  for (const auto& r : t.reports)
    if (r.lod == lod) return &r;
  return nullptr;
}

// The encoder's account of how a level was decimated into the next coarser
// one (null for the coarsest level and for streams).
void decimation_json(Json& j, const Table& t, int lod) {
  const LevelReport* r = report_of(t, lod);
  const bool decimated = r && lod + 1 < static_cast<int>(t.levels.size());
  j.key("removed");
  if (decimated) j.value(r->boundary_removed + r->inner_removed);
  else j.value(kUndefined);
  j.key("optimizer_used");
  if (decimated && t.kind == Kind::volume) j.value(optimizer_name(r->optimizer));
  else j.value(kUndefined);
}

void print_surface(const Table& t, int classes, Json* j) {
  if (j) j->key("levels").begin_array();
  else
    std::printf("%-8s %8s %10s %8s %8s %12s %12s %14s\n", "level", "NV", "GA", "QT1", "QT2", "min/max e.r.",
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
      j->key("edges").value(es.edges).key("ga").value(es.global_alpha);
      quality_fields(*j, qual);
      j->key("min_edge_ratio").value(es.min_edge_ratio).key("neighbour_max_edge_ratio").value(es.neighbour_max_ratio);
      j->key("neighbour_min_max_edge_ratio").value(es.neighbour_ratio_ratio);
      decimation_json(*j, t, it->lod);
      mec_json(*j, es);
      j->end_object();
    } else {
      // Thesis columns: QT1 = min/max edge ratio test, QT2 = angle test (mesh means).
      std::printf("Level %-2d %8zu %s %s %s %s %s %s\n", it->lod, m.points.size(), cell(es.global_alpha, 10, 6).c_str(),
                  cell(mean_or_null(qual.tri_edge), 8, 4).c_str(), cell(mean_or_null(qual.tri_angle), 8, 4).c_str(),
                  cell(es.min_edge_ratio, 12, 6).c_str(), cell(es.neighbour_max_ratio, 12, 6).c_str(),
                  cell(es.neighbour_ratio_ratio, 14, 6).c_str());
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

void print_volume_rows(const Table& t, int classes, Json* j) {
  const char* label = t.optimizer.empty() ? "stream" : t.optimizer.c_str();
  for (auto it = t.levels.rbegin(); it != t.levels.rend(); ++it) {
    const Mesh m = level_mesh(t.q, *it);
    const auto qual = quality::evaluate(m);
    const auto es = edge_stats(m, classes);
    const auto vl = volume_layers(*it);
    if (j) {
      j->begin_object();
      j->key("optimizer");
      if (t.optimizer.empty()) j->value(kUndefined);
      else j->value(t.optimizer);
      j->key("level").value(it->lod);
      j->key("vn").value(static_cast<std::uint64_t>(m.points.size())).key("cn").value(static_cast<std::uint64_t>(m.tetrahedra.size()));
      j->key("layers").begin_array();
      for (auto n : vl.layers) j->value(n);
      j->end_array();
      j->key("classification").begin_object();
      j->key("boundary_by_faces").value(vl.boundary_by_faces).key("boundary_by_solid_angle").value(vl.boundary_by_angle);
      j->key("disagreements").value(vl.disagreements).end_object();
      j->key("edges").value(es.edges).key("ga").value(es.global_alpha);
      quality_fields(*j, qual);
      decimation_json(*j, t, it->lod);
      mec_json(*j, es);
      j->end_object();
      continue;
    }
    std::printf("%-9s L%-2d %8zu %8zu %10s  %s %s %s %s %5llu  ", label, it->lod, m.points.size(), m.tetrahedra.size(),
                cell(es.global_alpha, 10, 6).c_str(), cell(mean_or_null(qual.qt1), 7, 4).c_str(),
                cell(mean_or_null(qual.qt2), 7, 4).c_str(), cell(mean_or_null(qual.qt3), 7, 4).c_str(),
                cell(mean_or_null(qual.qt4), 7, 4).c_str(), static_cast<unsigned long long>(vl.disagreements));
    for (auto n : vl.layers) std::printf(" %6llu", static_cast<unsigned long long>(n));
    std::printf("\n");
  }
}

bool parse_optimizer(const std::string& s, Optimizer& o) {
  if (s == "forward") o = Optimizer::forward;
  else if (s == "backward") o = Optimizer::backward;
  else if (s == "greedy") o = Optimizer::greedy;
  else if (s == "best") o = Optimizer::best;
  else return false;
  return true;
}

constexpr const char* kUsageText =
    "usage: hmc analyze IN [--levels N] [--ratio R] [--bits Q] [--kind K] [--boundary MODE]\n"
    "                      [--optimizer LIST] [--fidelity F] [--classes C] [--json]\n"
    "  IN is a mesh (encoded here; the options are those of hmc enc, except --levels, default 4)\n"
    "  or an .hmc stream (its decoded levels; only --classes and --json apply).\n"
    "  --optimizer: forward, backward, greedy or best, or a comma-separated list; a volume is\n"
    "  encoded once per entry (default forward,backward,greedy, the thesis' tables 4.7-4.12),\n"
    "  a surface once with the first (default best; surfaces have no interior vertices).\n";

}  // namespace

int cmd_analyze(int argc, char** argv) {
  Args a(argc, argv, 2, {"--json"},
         {"--bits", "--levels", "--ratio", "--classes", "--kind", "--boundary", "--optimizer", "--fidelity"});
  auto usage = [](const std::string& why) {
    std::fprintf(stderr, "hmc analyze: %s\n%s", why.c_str(), kUsageText);
    return static_cast<int>(kUsage);
  };
  EncodeOptions eo;
  eo.bits = static_cast<int>(a.get_int("--bits", 12, 1, 21));
  eo.levels = static_cast<int>(a.get_int("--levels", 4, 1, 64));
  const int classes = static_cast<int>(a.get_int("--classes", 16, 1, 64));
  if (!a.ok()) return usage(a.error());
  if (a.positional().size() != 1) return usage("need one input (mesh or .hmc stream)");
  if (const std::string bad = share_option(a, "--ratio", Share::positive, eo.removal_ratio); !bad.empty())
    return usage(bad);
  const std::string kind = a.get("--kind", "auto");
  if (kind == "points") eo.kind = Kind::points;
  else if (kind == "surface") eo.kind = Kind::surface;
  else if (kind == "volume") eo.kind = Kind::volume;
  else if (kind != "auto") return usage("--kind must be points, surface, volume or auto");
  const std::string bm = a.get("--boundary", "linear");
  if (bm == "constant") eo.boundary_mode = BoundaryMode::constant;
  else if (bm == "linear") eo.boundary_mode = BoundaryMode::linear;
  else if (bm == "adaptive") eo.boundary_mode = BoundaryMode::adaptive;
  else return usage("--boundary must be constant, linear or adaptive");
  const std::string fid = a.get("--fidelity", "shape");
  if (!parse_fidelity(fid, eo.fidelity)) return usage("--fidelity must be rule, topology, shape or exact");
  std::vector<Optimizer> optimizers;
  if (a.has("--optimizer")) {
    const std::string list = a.get("--optimizer");
    std::size_t from = 0;
    while (true) {
      const std::size_t comma = list.find(',', from);
      const std::string item = list.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
      Optimizer o;
      if (!parse_optimizer(item, o))
        return usage("--optimizer takes forward, backward, greedy or best, or a comma-separated list of them; got '" +
                     list + "'");
      if (std::find(optimizers.begin(), optimizers.end(), o) == optimizers.end()) optimizers.push_back(o);
      if (comma == std::string::npos) break;
      from = comma + 1;
    }
  }
  const std::string in = a.positional()[0];
  const bool is_stream = in.size() > 4 && in.substr(in.size() - 4) == ".hmc";
  if (is_stream)
    for (const char* o : {"--bits", "--levels", "--ratio", "--kind", "--boundary", "--optimizer", "--fidelity"})
      if (a.has(o)) return usage(std::string(o) + " is an encoder option: it does not apply to a stream");

  std::vector<Table> tables;
  if (is_stream) {
    auto bytes = io::read_file(in);
    if (!bytes) return report("cannot read " + in, bytes.error(), Stage::input);
    auto d = decode(reinterpret_cast<const std::uint8_t*>(bytes.value().data()), bytes.value().size());
    if (!d) return report(in, d.error(), Stage::input);
    if (!d.value().warning.empty()) std::fprintf(stderr, "hmc: warning: %s\n", d.value().warning.c_str());
    tables.push_back(Table{"", d.value().kind, d.value().quantizer, d.value().levels, {}, bytes.value().size()});
  } else {
    auto mesh = io::read_mesh(in);
    if (!mesh) return report("cannot read " + in, mesh.error(), Stage::input);
    const Kind k = eo.kind ? *eo.kind : !mesh.value().tetrahedra.empty() ? Kind::volume
                                        : !mesh.value().triangles.empty() ? Kind::surface : Kind::points;
    if (optimizers.empty())
      optimizers = k == Kind::volume ? std::vector<Optimizer>{Optimizer::forward, Optimizer::backward, Optimizer::greedy}
                                     : std::vector<Optimizer>{Optimizer::best};
    if (k != Kind::volume) optimizers.resize(1);  // no interior vertices to choose among
    for (Optimizer o : optimizers) {
      eo.optimizer = o;
      auto e = encode(mesh.value(), eo);
      if (!e) return report("cannot encode " + in, e.error(), Stage::input);
      tables.push_back(Table{optimizer_name(o), e.value().report.kind, e.value().report.quantizer, e.value().levels,
                             e.value().report.levels, e.value().bytes.size()});
    }
  }
  const Table& first = tables.front();
  Json j;
  Json* jp = a.flag("--json") ? &j : nullptr;
  if (jp) {
    j.begin_object().key("input").value(in).key("source").value(is_stream ? "stream" : "mesh");
    j.key("kind").value(kind_name(first.kind)).key("q").value(first.q.bits);
    j.key("options");
    if (is_stream) {
      j.value(kUndefined);
    } else {
      j.begin_object().key("bits").value(eo.bits).key("levels").value(eo.levels).key("ratio").value(eo.removal_ratio);
      j.key("boundary").value(boundary_mode_name(eo.boundary_mode)).key("fidelity").value(fid);
      j.key("optimizers").begin_array();
      for (const auto& t : tables) j.value(t.optimizer);
      j.end_array().end_object();
    }
    j.key("runs").begin_array();
    for (const auto& t : tables) {
      j.begin_object().key("optimizer");
      if (t.optimizer.empty()) j.value(kUndefined);
      else j.value(t.optimizer);
      j.key("levels").value(static_cast<std::uint64_t>(t.levels.size())).key("bytes").value(t.bytes).end_object();
    }
    j.end_array();
  } else {
    std::printf("%s: %s, q = %d, %zu level(s)", in.c_str(), kind_name(first.kind), first.q.bits, first.levels.size());
    if (!is_stream)
      std::printf("; ratio %g, boundary %s, fidelity %s", eo.removal_ratio, boundary_mode_name(eo.boundary_mode),
                  fid.c_str());
    std::printf("\n\n");
  }
  if (first.kind == Kind::volume) {
    if (jp) j.key("levels").begin_array();
    else
      std::printf("%-9s %-3s %8s %8s %10s  %7s %7s %7s %7s %5s   layers L0 L1 ...\n", "optimizer", "lvl", "VN", "CN",
                  "GA", "QT1", "QT2", "QT3", "QT4", "disag");
    for (const auto& t : tables) print_volume_rows(t, classes, jp);
    if (jp) j.end_array();
  } else {
    print_surface(first, classes, jp);
  }
  if (jp) {
    j.end_object();
    std::fputs(j.str().c_str(), stdout);
  }
  return kOk;
}

}  // namespace hmc::cli
