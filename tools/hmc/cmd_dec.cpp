// SPDX-License-Identifier: AGPL-3.0-or-later
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include "cli.hpp"
#include "tiles.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"

namespace hmc::cli {

namespace {

Mesh level_mesh(const Decoded& d, const DecodedLevel& level) {
  Mesh m;
  m.points.reserve(level.points.size());
  for (const auto& p : level.points) m.points.push_back(d.quantizer.dequantize(p));
  m.triangles = level.triangles;
  m.tetrahedra = level.tetrahedra;
  return m;
}

// Binary coordinates as 32-bit floats when that moves none of them by more
// than 1/16 of the quantization step: the file keeps the grid exactly and is
// half the size. Far from the origin (say, georeferenced data) it would not,
// and doubles are written.
bool float32_keeps_grid(const Mesh& m, double step) {
  for (const Vec3& p : m.points)
    for (double c : p)
      if (std::fabs(static_cast<double>(static_cast<float>(c)) - c) > step / 16) return false;
  return true;
}

// One progress call of the decoder: it starts on `level`'s points, or on
// its connectivity.
struct Phase {
  int level;
  bool rebuilding;
  std::chrono::steady_clock::time_point at;
};

// Seconds from each progress call to the next one (the last: to `end`), by
// (level, rebuilding). On one thread these are the phases themselves: a
// level's points (with its side information), then its Delaunay
// tetrahedralization and reconstruction. With a second thread a level's
// reconstruction overlaps the next level's phases, and the figures are the
// calling thread's time in each.
std::map<std::pair<int, bool>, double> seconds_by_phase(const std::vector<Phase>& phases,
                                                        std::chrono::steady_clock::time_point end) {
  std::map<std::pair<int, bool>, double> out;
  for (std::size_t i = 0; i < phases.size(); ++i) {
    const auto next = i + 1 < phases.size() ? phases[i + 1].at : end;
    out[{phases[i].level, phases[i].rebuilding}] += std::chrono::duration<double>(next - phases[i].at).count();
  }
  return out;
}

}  // namespace

int cmd_dec(int argc, char** argv) {
  Args a(argc, argv, 2, {"--json", "--points-only"},
         {"-o", "--output", "--level", "--all-levels", "--ext", "--canonical", "--max-points", "--max-levels", "--max-memory",
          "--coords", "--rebuild", "--threads", "--region"});
  DecodeOptions opt;
  opt.finest_level = static_cast<int>(a.get_int("--level", 0, 0, 63));
  opt.limits.max_points = static_cast<std::uint64_t>(
      a.get_int("--max-points", static_cast<long long>(opt.limits.max_points), 1, 1ll << 40));
  opt.limits.max_levels = static_cast<std::uint32_t>(a.get_int("--max-levels", 64, 1, 64));
  opt.limits.max_memory = static_cast<std::uint64_t>(a.get_int(
                              "--max-memory", static_cast<long long>(opt.limits.max_memory >> 20), 1, 1ll << 30))
                          << 20;
  opt.reconstruct = !a.flag("--points-only");
  // A second thread reconstructs a level, or tetrahedralizes the coarser
  // levels ahead, while the next level decodes.
  opt.threads = threads_option(a);
  // Rebuild what is written or shown: one output file needs one level's
  // connectivity, so the coarser levels' reconstructions (more than half
  // the work of a multi-level stream) are skipped; the summary table and
  // the per-level outputs show every level.
  const std::string rebuild = a.get("--rebuild", "auto");
  opt.rebuild_coarser_levels = rebuild == "all" || (rebuild == "auto" && ((!a.has("-o") && !a.has("--output")) ||
                                                                          a.has("--all-levels") || a.has("--canonical")));
  const std::string out = a.has("-o") ? a.get("-o") : a.get("--output");
  const std::string coords = a.get("--coords", "auto");
  if (a.ok() && rebuild != "auto" && rebuild != "all" && rebuild != "finest") {
    std::fprintf(stderr, "hmc dec: --rebuild must be all or finest, not '%s'\n", rebuild.c_str());
    return kUsage;
  }
  if (a.ok() && coords != "auto" && coords != "float" && coords != "double") {
    std::fprintf(stderr, "hmc dec: --coords must be auto, float or double, not '%s'\n", coords.c_str());
    return kUsage;
  }
  if (!a.ok() || a.positional().size() != 1) {
    std::fprintf(stderr,
                 "hmc dec: %s\nusage: hmc dec IN.hmc [-o OUT] [--level K] [--all-levels DIR [--ext EXT]] [--canonical DIR]\n"
                 "                  [--coords auto|float|double] [--rebuild all|finest] [--points-only] [--max-points N]\n"
                 "                  [--max-levels N] [--max-memory MIB] [--threads N] [--json]\n",
                 a.ok() ? "need one input stream" : a.error().c_str());
    return kUsage;
  }
  const std::string in = a.positional()[0];
  if (is_tiled(in)) return dec_tiled(a, opt);  // spec/tiles.md
  if (a.has("--region")) {
    std::fprintf(stderr, "hmc dec: --region needs a tiled model (a directory with tiles.json)\n");
    return kUsage;
  }
  // Progress on a terminal only: scripts reading stderr get no noise. The
  // progress calls are also timed, for --json's per-level phases.
  const bool tty = isatty(fileno(stderr)) != 0;
  // The callback must not throw, so it never allocates: room for two calls
  // per level of the most levels a stream may have (spec: 64).
  std::vector<Phase> phases;
  phases.reserve(128);
  opt.progress = [tty, &phases](int level, bool rebuilding) {
    if (phases.size() < phases.capacity()) phases.push_back({level, rebuilding, std::chrono::steady_clock::now()});
    if (!tty) return;
    std::fprintf(stderr, "\rhmc: decoding, level %d, %-12s", level, rebuilding ? "rebuilding" : "points");
    std::fflush(stderr);
  };
  const auto t0 = std::chrono::steady_clock::now();
  auto bytes = io::read_file(in, opt.limits.max_bytes);
  if (!bytes) return report("cannot read " + in, bytes.error(), Stage::input);
  const auto& b = bytes.value();
  auto dec = decode(reinterpret_cast<const std::uint8_t*>(b.data()), b.size(), opt);
  if (tty) std::fprintf(stderr, "\r%45s\r", "");
  if (!dec) return report(in, dec.error(), Stage::input);
  const auto t1 = std::chrono::steady_clock::now();
  const Decoded& d = dec.value();
  if (!d.warning.empty()) std::fprintf(stderr, "hmc: warning: %s: %s\n", in.c_str(), d.warning.c_str());
  const auto declared = static_cast<int>(d.declared_points.size());
  if (opt.finest_level > 0 && opt.finest_level >= declared)
    std::fprintf(stderr, "hmc: warning: %s: --level %d: the stream has levels 0 to %d; decoded its coarsest, level %d\n",
                 in.c_str(), opt.finest_level, declared - 1, declared - 1);
  else if (opt.finest_level > 0 && d.finest().lod > opt.finest_level)
    std::fprintf(stderr, "hmc: warning: %s: level %d is not in the stream; the finest decoded level is %d\n", in.c_str(),
                 opt.finest_level, d.finest().lod);

  Outputs written;
  auto options = [&](const Mesh& m) {
    io::WriteOptions wo;
    wo.protect_path = in;
    wo.float32 = coords == "float" || (coords == "auto" && float32_keeps_grid(m, d.quantizer.step));
    return wo;
  };
  if (!out.empty()) {
    const Mesh m = level_mesh(d, d.finest());
    auto w = io::write_mesh(out, m, io::Format::automatic, options(m));
    if (!w) return report("cannot write " + out, w.error(), Stage::output);
    written.add(out);
  }
  if (a.has("--all-levels")) {
    const std::string dir = a.get("--all-levels");
    if (!exists(dir)) written.add(dir);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return report("cannot create " + dir, Error{Status::io_error, ec.message()}, Stage::output);
    // PLY cannot hold tetrahedra: a volume's rebuilt levels default to
    // legacy VTK, everything else (surfaces, point sets) to PLY.
    bool tets = false;
    for (const auto& level : d.levels) tets = tets || !level.tetrahedra.empty();
    const std::string ext = a.get("--ext", tets ? "vtk" : "ply");
    for (const auto& level : d.levels) {
      const std::string path = (std::filesystem::path(dir) / ("level-" + std::to_string(level.lod) + "." + ext)).string();
      const Mesh m = level_mesh(d, level);
      auto w = io::write_mesh(path, m, io::Format::automatic, options(m));
      if (!w) return report("cannot write " + path, w.error(), Stage::output);
      written.add(path);
    }
  }
  if (a.has("--canonical")) {
    const std::string dir = a.get("--canonical");
    const bool existed = exists(dir);
    std::vector<DumpLevel> levels;
    for (const auto& l : d.levels) levels.push_back({l.lod, &l.points, &l.triangles, &l.tetrahedra, !opt.reconstruct});
    auto w = write_canonical_dump(dir, d.kind, d.quantizer, d.declared_points, levels);
    if (!w) return report("cannot write the canonical dump", w.error(), Stage::output);
    if (!existed) written.add(dir);
  }
  written.commit();
  const double secs = std::chrono::duration<double>(t1 - t0).count();
  if (a.flag("--json")) {
    Json j;
    j.begin_object();
    j.key("input").value(in).key("kind").value(kind_name(d.kind)).key("q").value(d.quantizer.bits);
    j.key("levels_declared").value(d.level_count()).key("truncated").value(d.truncated);
    if (!d.warning.empty()) j.key("warning").value(d.warning);
    j.key("decode_seconds").value(secs);
    j.key("levels").begin_array();
    const auto phase_seconds = seconds_by_phase(phases, t1);
    for (const auto& l : d.levels) {
      j.begin_object();
      j.key("level").value(l.lod).key("points").value(static_cast<std::uint64_t>(l.points.size()));
      j.key("triangles").value(static_cast<std::uint64_t>(l.triangles.size()));
      j.key("tetrahedra").value(static_cast<std::uint64_t>(l.tetrahedra.size()));
      j.key("rebuilt").value(l.rebuilt);
      j.key("stream_bytes").value(l.stream_bytes);
      if (const auto it = phase_seconds.find({l.lod, false}); it != phase_seconds.end())
        j.key("points_seconds").value(it->second);
      if (const auto it = phase_seconds.find({l.lod, true}); it != phase_seconds.end())
        j.key("rebuild_seconds").value(it->second);
      j.end_object();
    }
    j.end_array().end_object();
    std::fputs(j.str().c_str(), stdout);
  } else {
    std::printf("%s: %s, q = %d, %d level(s) declared, %zu decoded in %.3f s\n", in.c_str(), kind_name(d.kind),
                d.quantizer.bits, d.level_count(), d.levels.size(), secs);
    std::printf("%6s %10s %10s %10s %12s\n", "level", "points", "triangles", "tetrahedra", "stream bytes");
    // "-": connectivity not rebuilt (points only, or a coarser level when
    // only the finest one is written).
    auto count = [&](const DecodedLevel& l, std::size_t v) {
      return d.kind == Kind::points || l.rebuilt ? std::to_string(v) : std::string("-");
    };
    for (const auto& l : d.levels)
      std::printf("%6d %10zu %10s %10s %12llu\n", l.lod, l.points.size(), count(l, l.triangles.size()).c_str(),
                  count(l, l.tetrahedra.size()).c_str(), static_cast<unsigned long long>(l.stream_bytes));
  }
  return kOk;
}

}  // namespace hmc::cli
