// SPDX-License-Identifier: AGPL-3.0-or-later
// hmc tile-split: cut a model into the per-tile inputs of a tiled model
// (spec/tiles.md) on its one lattice, with a plan for the encoding jobs;
// hmc tile: run tools/hmc_tile.py, which encodes those jobs on Dask (or a
// process pool) and writes the tiled model.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli.hpp"
#include "hmc/codec.hpp"
#include "hmc/meshio.hpp"

namespace fs = std::filesystem;

namespace hmc::cli {

namespace {

using Box = std::array<std::int64_t, 6>;  // x0, y0, z0, x1, y1, z1 (half-open)

struct Leaf {
  Box box;
  std::size_t begin, end;  // range of `order`
};

// k-d split of the points order[b, e) (indices into `pts`) inside `box`, at
// the median of the axis along which they spread most, until a tile holds at
// most `cap` points. Cuts are integer planes: a point with coordinate < cut
// goes left.
void split(const std::vector<GridPoint>& pts, std::vector<std::uint32_t>& order, std::size_t b, std::size_t e,
           const Box& box, std::size_t cap, std::vector<Leaf>& leaves) {
  if (e - b <= cap) {
    leaves.push_back({box, b, e});
    return;
  }
  std::array<std::uint32_t, 3> lo{UINT32_MAX, UINT32_MAX, UINT32_MAX}, hi{0, 0, 0};
  for (std::size_t i = b; i < e; ++i)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], pts[order[i]][a]), hi[a] = std::max(hi[a], pts[order[i]][a]);
  std::array<int, 3> axes{0, 1, 2};
  std::stable_sort(axes.begin(), axes.end(), [&](int u, int v) { return hi[u] - lo[u] > hi[v] - lo[v]; });
  for (int a : axes) {
    if (hi[a] == lo[a]) continue;
    const std::size_t mid = b + (e - b) / 2;
    auto coord = [&](std::uint32_t i) { return pts[i][a]; };
    std::nth_element(order.begin() + b, order.begin() + mid, order.begin() + e,
                     [&](std::uint32_t u, std::uint32_t v) { return coord(u) < coord(v); });
    std::uint32_t cut = coord(order[mid]);
    if (cut == lo[a]) cut = lo[a] + 1;  // the median is the minimum: cut just above it
    const auto s = static_cast<std::size_t>(
        std::partition(order.begin() + b, order.begin() + e, [&](std::uint32_t i) { return coord(i) < cut; }) -
        order.begin());
    Box left = box, right = box;
    left[3 + a] = cut;
    right[a] = cut;
    split(pts, order, b, s, left, cap, leaves);
    split(pts, order, s, e, right, cap, leaves);
    return;
  }
  leaves.push_back({box, b, e});  // one point repeated: cannot happen for distinct points
}

bool in_box(const GridPoint& p, const Box& b, std::int64_t m) {
  for (int a = 0; a < 3; ++a)
    if (static_cast<std::int64_t>(p[a]) < b[a] - m || static_cast<std::int64_t>(p[a]) >= b[3 + a] + m) return false;
  return true;
}

bool boxes_meet(const Box& u, const Box& v, std::int64_t m) {
  for (int a = 0; a < 3; ++a)
    if (u[a] - m >= v[3 + a] || v[a] >= u[3 + a] + m) return false;
  return true;
}

std::string box_json(const Box& b) {
  std::string s = "[";
  for (int i = 0; i < 6; ++i) s += (i ? ", " : "") + std::to_string(b[i]);
  return s + "]";
}

template <std::size_t N>
void remap_simplices(const std::vector<std::array<std::uint32_t, N>>& in, const std::vector<std::uint32_t>& to_distinct,
                     std::vector<std::array<std::uint32_t, N>>& out) {
  out.reserve(in.size());
  for (const auto& s : in) {
    std::array<std::uint32_t, N> r;
    for (std::size_t i = 0; i < N; ++i) r[i] = to_distinct[s[i]];
    std::array<std::uint32_t, N> sorted = r;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end()) out.push_back(r);  // drop degenerate ones
  }
}

// The simplices whose corners all have a local index, bucketed by the tile of
// their first corner; appended to `out` renumbered.
template <std::size_t N>
void gather(const std::vector<std::array<std::uint32_t, N>>& all, const std::vector<std::vector<std::uint32_t>>& bucket,
            const std::vector<std::size_t>& near, const std::vector<std::uint32_t>& local,
            std::vector<std::array<std::uint32_t, N>>& out) {
  for (std::size_t u : near)
    for (std::uint32_t s : bucket[u]) {
      std::array<std::uint32_t, N> r;
      bool ok = true;
      for (std::size_t i = 0; i < N && ok; ++i) ok = (r[i] = local[all[s][i]]) != UINT32_MAX;
      if (ok) out.push_back(r);
    }
}

}  // namespace

int cmd_tile_split(int argc, char** argv) {
  Args a(argc, argv, 2, {}, {"-o", "--output", "--tile-points", "--bits", "--margin", "--kind", "--format"});
  const auto cap = static_cast<std::size_t>(a.get_int("--tile-points", 200000, 16, 1ll << 26));
  const int bits = static_cast<int>(a.get_int("--bits", 12, 1, 21));
  const long long margin_opt = a.get_int("--margin", -1, 0, 1 << 21);
  const std::string kind_s = a.get("--kind", "auto");
  const std::string out = a.has("-o") ? a.get("-o") : a.get("--output");
  if (!a.ok() || a.positional().size() != 1 || out.empty() ||
      (kind_s != "auto" && kind_s != "points" && kind_s != "surface" && kind_s != "volume")) {
    std::fprintf(stderr,
                 "hmc tile-split: %s\nusage: hmc tile-split IN -o WORKDIR [--tile-points N] [--bits Q] [--margin M]\n"
                 "                        [--kind points|surface|volume] [--format F]\n",
                 !a.ok() ? a.error().c_str() : "need one input file, -o WORKDIR and a known --kind");
    return kUsage;
  }
  const std::string in = a.positional()[0];
  io::Format in_format;
  if (!format_option(a, "hmc tile-split", in_format)) return kUsage;
  auto read = io::read_mesh(in, in_format);
  if (!read) return report("cannot read " + in, read.error(), Stage::input);
  Mesh mesh = std::move(read.value());
  Kind kind = !mesh.tetrahedra.empty() ? Kind::volume : !mesh.triangles.empty() ? Kind::surface : Kind::points;
  if (kind_s == "points") kind = Kind::points;
  if (kind_s == "surface") kind = Kind::surface;
  if (kind_s == "volume") kind = Kind::volume;
  auto fitted = fit_lattice(mesh.points, bits);
  if (!fitted) return report("cannot quantize " + in, fitted.error(), Stage::input);
  const ScalarQuantizer gq = fitted.value();

  // The model's lattice points, as encode() quantizes them (round half up,
  // clamped), merged as it merges them.
  const std::size_t n_in = mesh.points.size();
  std::vector<GridPoint> grid(n_in);
  const double top = static_cast<double>(gq.cells() - 1);
  for (std::size_t i = 0; i < n_in; ++i)
    for (int ax = 0; ax < 3; ++ax)
      grid[i][ax] = static_cast<std::uint32_t>(std::clamp(std::round((mesh.points[i][ax] - gq.origin[ax]) / gq.step), 0.0, top));
  std::vector<std::uint32_t> by_point(n_in);
  std::iota(by_point.begin(), by_point.end(), 0u);
  std::sort(by_point.begin(), by_point.end(), [&](std::uint32_t u, std::uint32_t v) { return grid[u] < grid[v]; });
  std::vector<GridPoint> pts;  // distinct, canonical order
  std::vector<std::uint32_t> to_distinct(n_in);
  for (std::uint32_t i : by_point) {
    if (pts.empty() || pts.back() != grid[i]) pts.push_back(grid[i]);
    to_distinct[i] = static_cast<std::uint32_t>(pts.size() - 1);
  }
  std::vector<GridPoint>().swap(grid);
  std::vector<std::uint32_t>().swap(by_point);
  // Each tile's input carries its points dequantized; the tile's encoder
  // quantizes them again on the same lattice and must find the same points.
  for (const auto& p : pts) {
    const Vec3 v = gq.dequantize(p);
    for (int ax = 0; ax < 3; ++ax)
      if (std::round((v[ax] - gq.origin[ax]) / gq.step) != static_cast<double>(p[ax])) {
        std::fprintf(stderr, "hmc tile-split: %s: the lattice does not round-trip (origin too far from the points for its step)\n",
                     in.c_str());
        return kInput;
      }
  }
  std::vector<Triangle> tris;
  std::vector<Tetrahedron> tets;
  if (kind == Kind::surface) remap_simplices(mesh.triangles, to_distinct, tris);
  if (kind == Kind::volume) remap_simplices(mesh.tetrahedra, to_distinct, tets);
  mesh = Mesh{};
  std::vector<std::uint32_t>().swap(to_distinct);

  // The points' bounding box (lattice units): the margin of a point set
  // without connectivity, and the diagonal every tile's encoder measures
  // its tolerances against (hmc enc --tolerance-diagonal).
  std::array<std::uint32_t, 3> box_lo{UINT32_MAX, UINT32_MAX, UINT32_MAX}, box_hi{0, 0, 0};
  for (const auto& p : pts)
    for (int ax = 0; ax < 3; ++ax) box_lo[ax] = std::min(box_lo[ax], p[ax]), box_hi[ax] = std::max(box_hi[ax], p[ax]);
  double diagonal = 0;
  for (int ax = 0; ax < 3 && !pts.empty(); ++ax) diagonal += double(box_hi[ax] - box_lo[ax]) * double(box_hi[ax] - box_lo[ax]);
  diagonal = std::sqrt(diagonal);

  // Margin: 4 mean edge lengths of the connectivity given, in lattice units.
  std::int64_t margin = 0;
  if (margin_opt >= 0) {
    margin = margin_opt;
  } else if (kind != Kind::points) {
    double sum = 0;
    std::uint64_t count = 0;
    auto edge = [&](std::uint32_t u, std::uint32_t v) {
      double d2 = 0;
      for (int ax = 0; ax < 3; ++ax) {
        const double d = double(pts[u][ax]) - double(pts[v][ax]);
        d2 += d * d;
      }
      sum += std::sqrt(d2);
      ++count;
    };
    for (const auto& t : tris) edge(t[0], t[1]), edge(t[1], t[2]), edge(t[2], t[0]);
    for (const auto& t : tets)
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) edge(t[i], t[j]);
    if (count) {
      margin = static_cast<std::int64_t>(std::ceil(4 * sum / double(count)));
    } else {  // no connectivity given: the spacing of as many points spread through their box
      double vol = 1;
      for (int ax = 0; ax < 3; ++ax) vol *= double(box_hi[ax] - box_lo[ax] + 1);
      margin = static_cast<std::int64_t>(std::ceil(4 * std::cbrt(vol / double(pts.size()))));
    }
  }

  std::vector<std::uint32_t> order(pts.size());
  std::iota(order.begin(), order.end(), 0u);
  std::vector<Leaf> leaves;
  const auto cells = static_cast<std::int64_t>(gq.cells());
  split(pts, order, 0, order.size(), Box{0, 0, 0, cells, cells, cells}, cap, leaves);
  const std::size_t n_tiles = leaves.size();
  std::vector<std::uint32_t> owner(pts.size());
  for (std::size_t t = 0; t < n_tiles; ++t)
    for (std::size_t i = leaves[t].begin; i < leaves[t].end; ++i) owner[order[i]] = static_cast<std::uint32_t>(t);
  std::fprintf(stderr, "hmc tile-split: %s: %zu points, %s, q = %d, %zu tiles of at most %zu points, margin %lld\n",
               in.c_str(), pts.size(), kind_name(kind), bits, n_tiles, cap, static_cast<long long>(margin));

  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) return report("cannot create " + out, Error{Status::io_error, ec.message()}, Stage::output);
  std::vector<std::vector<std::uint32_t>> tri_bucket(n_tiles), tet_bucket(n_tiles);
  for (std::size_t s = 0; s < tris.size(); ++s)
    tri_bucket[owner[*std::min_element(tris[s].begin(), tris[s].end())]].push_back(static_cast<std::uint32_t>(s));
  for (std::size_t s = 0; s < tets.size(); ++s)
    tet_bucket[owner[*std::min_element(tets[s].begin(), tets[s].end())]].push_back(static_cast<std::uint32_t>(s));

  std::string plan = "{\n  \"kind\": \"" + std::string(kind_name(kind)) + "\",\n  \"q\": " + std::to_string(bits) +
                     ",\n  \"origin\": [" + g17(gq.origin[0]) + ", " + g17(gq.origin[1]) + ", " + g17(gq.origin[2]) +
                     "],\n  \"step\": " + g17(gq.step) + ",\n  \"margin\": " + std::to_string(margin) +
                     ",\n  \"diagonal\": " + g17(diagonal) +
                     ",\n  \"points\": " + std::to_string(pts.size()) + ",\n  \"tiles\": [\n";
  std::vector<std::uint32_t> local(pts.size(), UINT32_MAX);
  const char* ext = kind == Kind::volume ? ".vtk" : ".ply";
  for (std::size_t t = 0; t < n_tiles; ++t) {
    const Leaf& leaf = leaves[t];
    std::vector<std::size_t> near;
    for (std::size_t u = 0; u < n_tiles; ++u)
      if (boxes_meet(leaf.box, leaves[u].box, margin)) near.push_back(u);
    std::vector<std::uint32_t> members;
    for (std::size_t u : near)
      for (std::size_t i = leaves[u].begin; i < leaves[u].end; ++i)
        if (u == t || in_box(pts[order[i]], leaf.box, margin)) members.push_back(order[i]);
    std::sort(members.begin(), members.end());
    Mesh tile;
    tile.points.reserve(members.size());
    for (std::size_t i = 0; i < members.size(); ++i) {
      local[members[i]] = static_cast<std::uint32_t>(i);
      tile.points.push_back(gq.dequantize(pts[members[i]]));
    }
    gather(tris, tri_bucket, near, local, tile.triangles);
    gather(tets, tet_bucket, near, local, tile.tetrahedra);
    for (std::uint32_t m : members) local[m] = UINT32_MAX;
    Box bounds{cells, cells, cells, 0, 0, 0};
    for (std::size_t i = leaf.begin; i < leaf.end; ++i)
      for (int ax = 0; ax < 3; ++ax) {
        bounds[ax] = std::min<std::int64_t>(bounds[ax], pts[order[i]][ax]);
        bounds[3 + ax] = std::max<std::int64_t>(bounds[3 + ax], pts[order[i]][ax]);
      }
    char name[32];
    std::snprintf(name, sizeof name, "tile-%05zu", t);
    const std::string input = std::string(name) + ext;
    io::WriteOptions wo;
    wo.binary = true;
    wo.float32 = false;
    auto w = io::write_mesh((fs::path(out) / input).string(), tile, io::Format::automatic, wo);
    if (!w) return report("cannot write " + input, w.error(), Stage::output);
    plan += std::string("    {\"input\": \"") + input + "\", \"file\": \"" + name + ".hmc\", \"box\": " + box_json(leaf.box) +
            ", \"bounds\": " + box_json(bounds) + ", \"points\": " + std::to_string(leaf.end - leaf.begin) +
            ", \"input_points\": " + std::to_string(members.size()) + "}" + (t + 1 < n_tiles ? ",\n" : "\n");
    if (isatty(fileno(stderr))) {
      std::fprintf(stderr, "\rhmc tile-split: wrote tile %zu of %zu", t + 1, n_tiles);
      std::fflush(stderr);
    }
  }
  if (isatty(fileno(stderr))) std::fprintf(stderr, "\n");
  plan += "  ]\n}\n";
  auto w = io::write_file_atomic((fs::path(out) / "plan.json").string(), plan);
  if (!w) return report("cannot write plan.json", w.error(), Stage::output);
  return kOk;
}

int cmd_tile(int argc, char** argv) {
  // The encoding jobs run in Python (Dask); find the script beside this
  // program: <bin>/../share/hmc/hmc_tile.py (build tree and installs alike).
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  std::string script = std::getenv("HMC_TILE_SCRIPT") ? std::getenv("HMC_TILE_SCRIPT") : "";
  if (script.empty() && !ec) script = (exe.parent_path().parent_path() / "share" / "hmc" / "hmc_tile.py").string();
  if (script.empty() || !fs::exists(script)) {
    std::fprintf(stderr, "hmc tile: cannot find hmc_tile.py (looked for %s; set HMC_TILE_SCRIPT)\n", script.c_str());
    return kInternal;
  }
  // Debian's python3 has python3-dask; a python3 earlier on PATH may not.
  std::string python = std::getenv("HMC_PYTHON") ? std::getenv("HMC_PYTHON") : "";
  if (python.empty()) python = access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  std::vector<std::string> args{python, script, "--hmc", ec ? std::string(argv[0]) : exe.string()};
  for (int i = 2; i < argc; ++i) args.emplace_back(argv[i]);
  std::vector<char*> cargs;
  for (auto& s : args) cargs.push_back(s.data());
  cargs.push_back(nullptr);
  std::fflush(stdout);
  execvp(python.c_str(), cargs.data());
  std::fprintf(stderr, "hmc tile: cannot run %s: %s\n", python.c_str(), std::strerror(errno));
  return kInternal;
}

}  // namespace hmc::cli
