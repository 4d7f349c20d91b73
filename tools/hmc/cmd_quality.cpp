// SPDX-License-Identifier: AGPL-3.0-or-later
#include <cstdio>
#include <string>

#include "cli.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"
#include "hmc/quality.hpp"

namespace hmc::cli {

namespace {

void stats_json(Json& j, const char* key, const quality::Stats& s) {
  j.key(key).begin_object();
  j.key("count").value(static_cast<std::uint64_t>(s.count)).key("mean").value(s.mean);
  j.key("min").value(s.min).key("max").value(s.max);
  j.key("histogram").begin_array();
  for (auto h : s.histogram) j.value(static_cast<std::uint64_t>(h));
  j.end_array().end_object();
}

void stats_row(const char* name, const char* what, const quality::Stats& s) {
  if (!s.count) return;
  std::printf("%-9s %-34s %9zu %8.4f %8.4f %8.4f  ", name, what, s.count, s.mean, s.min, s.max);
  for (auto h : s.histogram) std::printf(" %5.1f", 100.0 * static_cast<double>(h) / static_cast<double>(s.count));
  std::printf("\n");
}

}  // namespace

/// Quality of one mesh: shared by `hmc quality` on files and, per level, on streams.
void print_quality(const quality::MeshQuality& q) {
  std::printf("%-9s %-34s %9s %8s %8s %8s   histogram %% in [0,.1) ... [.9,1]\n", "test", "", "elements", "mean",
              "min", "max");
  stats_row("tri_angle", "sin(3*theta_min/2)", q.tri_angle);
  stats_row("tri_edge", "Lmin/Lmax", q.tri_edge);
  stats_row("qt1", "radius ratio 3*r_in/R_out", q.qt1);
  stats_row("qt2", "2*sqrt(6)*r_in/L_max", q.qt2);
  stats_row("qt3", "12*(3V)^(2/3)/sum L^2", q.qt3);
  stats_row("qt4", "min solid angle, normalised", q.qt4);
}

void quality_json(Json& j, const quality::MeshQuality& q) {
  // Whole-mesh means under fixed keys (scripts rely on them), details beside.
  j.key("tri_angle").value(q.tri_angle.mean).key("tri_edge").value(q.tri_edge.mean);
  j.key("qt1").value(q.qt1.mean).key("qt2").value(q.qt2.mean).key("qt3").value(q.qt3.mean).key("qt4").value(q.qt4.mean);
  j.key("triangles").value(static_cast<std::uint64_t>(q.tri_angle.count));
  j.key("tetrahedra").value(static_cast<std::uint64_t>(q.qt1.count));
  j.key("details").begin_object();
  stats_json(j, "tri_angle", q.tri_angle);
  stats_json(j, "tri_edge", q.tri_edge);
  stats_json(j, "qt1", q.qt1);
  stats_json(j, "qt2", q.qt2);
  stats_json(j, "qt3", q.qt3);
  stats_json(j, "qt4", q.qt4);
  j.end_object();
}

int cmd_quality(int argc, char** argv) {
  Args a(argc, argv, 2, {"--json"}, {});
  if (!a.ok() || a.positional().size() != 1) {
    std::fprintf(stderr, "hmc quality: %s\nusage: hmc quality MESH|STREAM.hmc [--json]\n",
                 a.ok() ? "need one mesh file" : a.error().c_str());
    return kUsage;
  }
  const std::string in = a.positional()[0];
  if (in.size() > 4 && in.compare(in.size() - 4, 4, ".hmc") == 0) {
    // A stream: every decoded level, after reconstruction.
    auto bytes = io::read_file(in);
    if (!bytes) return report("cannot read " + in, bytes.error(), Stage::input);
    auto d = decode(reinterpret_cast<const std::uint8_t*>(bytes.value().data()), bytes.value().size());
    if (!d) return report(in, d.error(), Stage::input);
    Json j;
    if (a.flag("--json")) j.begin_object().key("input").value(in).key("levels").begin_array();
    for (const auto& l : d.value().levels) {
      Mesh m;
      for (const auto& p : l.points) m.points.push_back(d.value().quantizer.dequantize(p));
      m.triangles = l.triangles;
      m.tetrahedra = l.tetrahedra;
      const auto q = quality::evaluate(m);
      if (a.flag("--json")) {
        j.begin_object().key("level").value(l.lod).key("points").value(static_cast<std::uint64_t>(m.points.size()));
        quality_json(j, q);
        j.end_object();
      } else {
        std::printf("%s level %d: %zu points, %zu triangles, %zu tetrahedra\n", in.c_str(), l.lod, m.points.size(),
                    m.triangles.size(), m.tetrahedra.size());
        print_quality(q);
        std::printf("\n");
      }
    }
    if (a.flag("--json")) {
      j.end_array().end_object();
      std::fputs(j.str().c_str(), stdout);
    }
    return kOk;
  }
  auto mesh = io::read_mesh(in);
  if (!mesh) return report("cannot read " + in, mesh.error(), Stage::input);
  const auto q = quality::evaluate(mesh.value());
  if (a.flag("--json")) {
    Json j;
    j.begin_object();
    j.key("input").value(in).key("points").value(static_cast<std::uint64_t>(mesh.value().points.size()));
    quality_json(j, q);
    j.end_object();
    std::fputs(j.str().c_str(), stdout);
  } else {
    std::printf("%s: %zu points, %zu triangles, %zu tetrahedra\n", in.c_str(), mesh.value().points.size(),
                mesh.value().triangles.size(), mesh.value().tetrahedra.size());
    print_quality(q);
  }
  return kOk;
}

}  // namespace hmc::cli
