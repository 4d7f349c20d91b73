// SPDX-License-Identifier: AGPL-3.0-or-later
// The progressive stream: levels coarse to fine, independent sets removed
// per level, prefixes that decode to coarser levels, truncation.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "codec/format.hpp"
#include "container/container.hpp"
#include "delaunay/delaunay.hpp"
#include "util/morton.hpp"
#include "hmc/codec.hpp"
#include "samples.hpp"
#include "support/why.hpp"

using namespace hmc;
using namespace hmc::detail;

namespace {

Encoded encode_levels(const Mesh& m, int levels, Optimizer o = Optimizer::best,
                      BoundaryMode b = BoundaryMode::linear, Fidelity f = Fidelity::shape) {
  EncodeOptions opt;
  opt.levels = levels;
  opt.optimizer = o;
  opt.boundary_mode = b;
  opt.fidelity = f;
  auto e = encode(m, opt);
  REQUIRE_MESSAGE(e.ok(), hmc::testgen::why(e));
  return std::move(e).value();
}

// Edges of a level's mesh, as pairs of point indices.
std::set<std::pair<std::uint32_t, std::uint32_t>> edges_of(const DecodedLevel& l) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> e;
  auto add = [&](std::uint32_t a, std::uint32_t b) { e.insert({std::min(a, b), std::max(a, b)}); };
  for (const auto& t : l.triangles)
    for (int k = 0; k < 3; ++k) add(t[k], t[(k + 1) % 3]);
  for (const auto& t : l.tetrahedra)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) add(t[i], t[j]);
  return e;
}

// Every level removes an independent set of the finer level's mesh: no
// two points the finer level adds (that the coarser lacks) are adjacent.
void check_independent(const Encoded& e) {
  REQUIRE(e.levels.size() >= 2);
  for (std::size_t i = 1; i < e.levels.size(); ++i) {
    const auto& coarse = e.levels[i - 1].points;
    const auto& fine = e.levels[i];
    CHECK(std::includes(fine.points.begin(), fine.points.end(), coarse.begin(), coarse.end()));
    std::vector<std::uint8_t> added(fine.points.size(), 0);
    for (std::size_t v = 0; v < fine.points.size(); ++v)
      added[v] = !std::binary_search(coarse.begin(), coarse.end(), fine.points[v]);
    std::size_t adjacent = 0;
    for (const auto& [a, b] : edges_of(fine)) adjacent += added[a] && added[b];
    CAPTURE(fine.lod);
    CHECK(adjacent == 0);
    CHECK(std::count(added.begin(), added.end(), 1) > 0);
  }
}


}  // namespace

TEST_CASE("every level removes an independent set, for every input, mode and optimiser") {
  const Mesh sphere = samples::uv_sphere(18, 36), torus = samples::torus(48, 20), ball = samples::random_ball(700, 5);
  for (BoundaryMode b : {BoundaryMode::constant, BoundaryMode::linear, BoundaryMode::adaptive}) {
    CAPTURE(boundary_mode_name(b));
    check_independent(encode_levels(sphere, 4, Optimizer::best, b));
    check_independent(encode_levels(torus, 4, Optimizer::best, b));
  }
  // A volume mesh given as input: a lattice block's Delaunay tetrahedra.
  Mesh vol = samples::lattice(7, 6, 5);
  {
    std::vector<GridPoint> g;
    for (const auto& p : vol.points) g.push_back({std::uint32_t(p[0]), std::uint32_t(p[1]), std::uint32_t(p[2])});
    const auto dt = delaunay(g);  // lattice order is canonical order
    vol.tetrahedra = dt.tets;
  }
  for (Optimizer o : {Optimizer::forward, Optimizer::backward, Optimizer::greedy, Optimizer::best}) {
    CAPTURE(optimizer_name(o));
    const auto e = encode_levels(vol, 3, o);
    CHECK(e.report.kind == Kind::volume);
    check_independent(e);
  }
  for (Optimizer o : {Optimizer::forward, Optimizer::backward, Optimizer::greedy, Optimizer::best}) {
    CAPTURE(optimizer_name(o));
    check_independent(encode_levels(ball, 4, o));  // points kind: decimated as the volume of their tetrahedra
  }
}

TEST_CASE("decoded levels equal the encoder's, coarsest first, each a subset of the next") {
  const auto e = encode_levels(samples::torus(40, 16), 4);
  REQUIRE(e.levels.size() == 4);
  auto d = decode(e.bytes.data(), e.bytes.size());
  REQUIRE_MESSAGE(d.ok(), hmc::testgen::why(d));
  REQUIRE(d.value().levels.size() == 4);
  for (std::size_t i = 0; i < 4; ++i) {
    CAPTURE(i);
    const auto& a = e.levels[i];
    const auto& b = d.value().levels[i];
    CHECK(a.lod == b.lod);
    CHECK(b.lod == 3 - static_cast<int>(i));
    CHECK(a.points == b.points);
    CHECK(a.triangles == b.triangles);
    CHECK(a.stream_bytes == b.stream_bytes);
  }
  CHECK(d.value().finest().points == e.points);
  CHECK(e.report.levels.size() == 4);
  CHECK(e.report.levels.back().points == e.points.size());
}

TEST_CASE("every prefix ending on a level boundary decodes to that level; cuts elsewhere to the last complete one") {
  const auto e = encode_levels(samples::uv_sphere(14, 28), 3);
  REQUIRE(e.levels.size() == 3);
  const auto& b = e.bytes;
  for (std::size_t i = 0; i < e.levels.size(); ++i) {
    const auto& lvl = e.levels[i];
    auto d = decode(b.data(), lvl.stream_bytes);
    REQUIRE_MESSAGE(d.ok(), hmc::testgen::why(d));
    CHECK(d.value().finest().lod == lvl.lod);
    CHECK(d.value().finest().points == lvl.points);
    CHECK(d.value().finest().triangles == lvl.triangles);
    CHECK(d.value().truncated == (lvl.lod > 0));
  }
  // Cut anywhere: the finest complete level before the cut, or an error
  // before the first level.
  for (std::size_t n = 0; n < b.size(); n += 7) {
    auto d = decode(b.data(), n);
    std::size_t complete = 0;
    for (const auto& l : e.levels) complete += l.stream_bytes <= n;
    CAPTURE(n);
    if (complete == 0) {
      CHECK(d.status() == Status::truncated);
    } else {
      REQUIRE(d.ok());
      CHECK(d.value().levels.size() == complete);
      CHECK_FALSE(d.value().warning.empty());
    }
  }
}

TEST_CASE("finest_level stops at a coarser level") {
  const auto e = encode_levels(samples::torus(40, 16), 3);
  DecodeOptions o;
  o.finest_level = 1;
  auto d = decode(e.bytes.data(), e.bytes.size(), o);
  REQUIRE(d.ok());
  CHECK(d.value().finest().lod == 1);
  CHECK(d.value().levels.size() == 2);
  CHECK_FALSE(d.value().truncated);
}

TEST_CASE("rebuilding only the finest decoded level gives it the same mesh and skips the others") {
  // Closed and open surfaces (the open one's finer levels inherit the
  // coarser level's border, which must be resolved through levels that are
  // not rebuilt) and a volume.
  struct Case {
    const char* name;
    Encoded e;
  };
  EncodeOptions vol;
  vol.levels = 3;
  vol.kind = Kind::volume;
  auto v = encode(samples::random_ball(500, 5), vol);
  REQUIRE(v.ok());
  std::vector<Case> cases;
  cases.push_back({"torus", encode_levels(samples::torus(40, 16), 4)});
  cases.push_back({"open surface", encode_levels(samples::height_field(20, 0.15), 4)});
  cases.push_back({"volume", std::move(v).value()});
  for (const auto& one : cases) {
    const std::string name = one.name;  // not a structured binding: CAPTURE's lambda cannot capture those (clang)
    const Encoded& e = one.e;
    CAPTURE(name);
    REQUIRE(e.levels.size() >= 3);
    if (name == "open surface") {
      // At least one finer level inherits its border (RCON flag bit 3).
      const auto view = parse_container(e.bytes.data(), e.bytes.size(), kEnd);
      int inherits = 0;
      for (const auto& c : view.chunks)
        if (c.type == kRecon && c.length > 0 && (c.payload[0] & 8)) ++inherits;
      REQUIRE(inherits > 0);
    }
    DecodeOptions finest;
    finest.rebuild_coarser_levels = false;
    // Every prefix that ends on a level boundary: its last level is rebuilt
    // exactly as the encoder planned it, the coarser ones carry points only.
    for (std::size_t i = 0; i < e.levels.size(); ++i) {
      CAPTURE(i);
      auto d = decode(e.bytes.data(), e.levels[i].stream_bytes, finest);
      REQUIRE_MESSAGE(d.ok(), hmc::testgen::why(d));
      const auto& got = d.value().levels;
      REQUIRE(got.size() == i + 1);
      for (std::size_t j = 0; j <= i; ++j) {
        CAPTURE(j);
        CHECK(got[j].points == e.levels[j].points);
        CHECK(got[j].rebuilt == (j == i));
        if (j < i) CHECK((got[j].triangles.empty() && got[j].tetrahedra.empty()));
      }
      CHECK(got[i].triangles == e.levels[i].triangles);
      CHECK(got[i].tetrahedra == e.levels[i].tetrahedra);
      CHECK(got[i].triangles.size() + got[i].tetrahedra.size() > 0);
    }
    // A requested coarser level is the one rebuilt.
    finest.finest_level = 1;
    auto d = decode(e.bytes.data(), e.bytes.size(), finest);
    REQUIRE(d.ok());
    const std::size_t at = e.levels.size() - 2;  // level 1
    REQUIRE(d.value().levels.size() == at + 1);
    CHECK(d.value().finest().lod == 1);
    CHECK(d.value().finest().rebuilt);
    CHECK(d.value().finest().triangles == e.levels[at].triangles);
    CHECK(d.value().finest().tetrahedra == e.levels[at].tetrahedra);
    // The default rebuilds every level.
    auto all = decode(e.bytes.data(), e.bytes.size());
    REQUIRE(all.ok());
    for (const auto& l : all.value().levels) CHECK(l.rebuilt);
  }
}

TEST_CASE("decoding reports progress: each level's points, then each level it rebuilds") {
  const auto e = encode_levels(samples::torus(40, 16), 3);
  REQUIRE(e.levels.size() == 3);
  std::vector<std::pair<int, bool>> calls;
  DecodeOptions o;
  o.progress = [&](int level, bool rebuilding) { calls.emplace_back(level, rebuilding); };
  REQUIRE(decode(e.bytes.data(), e.bytes.size(), o).ok());
  CHECK(calls == std::vector<std::pair<int, bool>>{{2, false}, {2, true}, {1, false}, {1, true}, {0, false}, {0, true}});
  calls.clear();
  o.rebuild_coarser_levels = false;
  REQUIRE(decode(e.bytes.data(), e.bytes.size(), o).ok());
  CHECK(calls == std::vector<std::pair<int, bool>>{{2, false}, {1, false}, {0, false}, {0, true}});
  calls.clear();
  o.reconstruct = false;
  REQUIRE(decode(e.bytes.data(), e.bytes.size(), o).ok());
  CHECK(calls == std::vector<std::pair<int, bool>>{{2, false}, {1, false}, {0, false}});
  // A cut stream in finest-only mode: its last level is rebuilt at the end.
  calls.clear();
  o.reconstruct = true;
  REQUIRE(decode(e.bytes.data(), e.levels[1].stream_bytes, o).ok());
  CHECK(calls == std::vector<std::pair<int, bool>>{{2, false}, {1, false}, {1, true}});
}

TEST_CASE("stream structure errors around refinement layers") {
  const auto e = encode_levels(samples::uv_sphere(12, 24), 3);
  auto v = parse_container(e.bytes.data(), e.bytes.size(), kEnd);
  std::vector<std::pair<ChunkType, std::vector<std::uint8_t>>> chunks;
  for (const auto& c : v.chunks) chunks.emplace_back(c.type, std::vector<std::uint8_t>(c.payload, c.payload + c.length));
  auto build = [](const std::vector<std::pair<ChunkType, std::vector<std::uint8_t>>>& cs) {
    ContainerWriter w;
    for (const auto& [t, p] : cs) w.chunk(t, p);
    return w.finish();
  };
  auto status = [&](const std::vector<std::pair<ChunkType, std::vector<std::uint8_t>>>& cs) {
    const auto b = build(cs);
    return decode(b.data(), b.size()).status();
  };
  REQUIRE(status(chunks) == Status::ok);
  std::size_t refn = 0;
  for (std::size_t i = 0; i < chunks.size(); ++i)
    if (chunks[i].first == kRefinement) {
      refn = i;
      break;
    }
  REQUIRE(refn > 0);
  auto c = chunks;
  c.insert(c.end() - 1, c[refn]);  // an extra REFN beyond the declared levels
  c.insert(c.end() - 1, c[refn + 1]);
  CHECK(status(c) == Status::bad_chunk);
  // Unknown refinement coders, among them those that spec 0.25 removed (2-6);
  // the same for the base layer (removed: 1-4).
  for (const int coder : {2, 3, 4, 5, 6, 8, 255}) {
    CAPTURE(coder);
    c = chunks;
    c[refn].second[0] = static_cast<std::uint8_t>(coder);
    CHECK(status(c) == Status::bad_layer);
  }
  for (std::size_t i = 0; i < chunks.size(); ++i) {
    if (chunks[i].first != kBaseLayer) continue;
    for (const int coder : {1, 2, 3, 4, 6, 255}) {
      CAPTURE(coder);
      c = chunks;
      c[i].second[0] = static_cast<std::uint8_t>(coder);
      const auto b = build(c);
      const auto d = decode(b.data(), b.size());
      CHECK(d.status() == Status::bad_layer);
      CHECK(d.error().message.find("unknown coder") != std::string::npos);
    }
  }
  c = chunks;
  c[refn].second.push_back(0);  // trailing byte in the layer
  CHECK(status(c) != Status::ok);
  c = chunks;
  // REFN before BASE
  std::size_t base = 0;
  for (std::size_t i = 0; i < c.size(); ++i)
    if (c[i].first == kBaseLayer) base = i;
  std::swap(c[base], c[refn]);
  CHECK(status(c) == Status::bad_chunk);
}

TEST_CASE("fast_decode: plain octrees without neighbours, the same levels, a larger stream") {
  const Mesh m = samples::torus(60, 24);
  EncodeOptions opt;
  opt.levels = 4;
  auto small = encode(m, opt);
  opt.fast_decode = true;
  auto fast = encode(m, opt);
  REQUIRE_MESSAGE(small.ok(), hmc::testgen::why(small));
  REQUIRE_MESSAGE(fast.ok(), hmc::testgen::why(fast));
  const auto& e = fast.value();
  REQUIRE(e.levels.size() == small.value().levels.size());
  for (std::size_t i = 0; i < e.levels.size(); ++i) {
    CAPTURE(i);
    CHECK(e.levels[i].points == small.value().levels[i].points);
    CHECK(e.levels[i].triangles == small.value().levels[i].triangles);
  }
  MESSAGE("4-level torus: ", e.bytes.size(), " bytes with fast_decode, ", small.value().bytes.size(), " without");
  CHECK(e.bytes.size() > small.value().bytes.size());
  // BASE coder 0; every REFN with neighbours 0 (the first 4 bits of coders
  // 0 and 7 after the coder byte).
  const ContainerView v = parse_container(e.bytes.data(), e.bytes.size(), kEnd);
  int layers = 0;
  for (const ChunkView& c : v.chunks) {
    if (c.type == kBaseLayer) CHECK(c.payload[0] == 0);
    if (c.type != kRefinement) continue;
    ++layers;
    CHECK((c.payload[0] == 0 || c.payload[0] == 7));  // the exact coders, the only ones left
    CHECK((c.payload[1] >> 4) == 0);
  }
  CHECK(layers == 3);
  auto d = decode(e.bytes.data(), e.bytes.size());
  REQUIRE_MESSAGE(d.ok(), hmc::testgen::why(d));
  CHECK(d.value().finest().points == e.points);
  CHECK(d.value().finest().triangles == small.value().levels.back().triangles);
}

TEST_CASE("fit_coarse_levels: coarser levels of a torus stay on it, one closed piece of genus 1") {
  // samples::torus(60, 24): major radius 1, minor 0.35. A point's distance
  // to the torus is | |(rho - 1, z)| - 0.35 |, rho its distance to the z axis.
  const Mesh m = samples::torus(60, 24);
  auto off_torus = [](const Vec3& p) {
    const double rho = std::sqrt(p[0] * p[0] + p[1] * p[1]);
    return std::abs(std::hypot(rho - 1.0, p[2]) - 0.35);
  };
  EncodeOptions opt;
  opt.levels = 4;
  opt.removal_ratio = 0.5;
  auto plain = encode(m, opt);
  opt.fit_coarse_levels = true;
  auto fit = encode(m, opt);
  REQUIRE_MESSAGE(plain.ok(), hmc::testgen::why(plain));
  REQUIRE_MESSAGE(fit.ok(), hmc::testgen::why(fit));
  const Encoded& e = fit.value();
  auto d = decode(e.bytes.data(), e.bytes.size());
  REQUIRE_MESSAGE(d.ok(), hmc::testgen::why(d));
  REQUIRE(d.value().levels.size() == e.levels.size());
  REQUIRE(e.levels.size() == 4);
  // Worst distance from the torus of a level's vertices, edge midpoints and
  // triangle centroids (input units), and its topology.
  auto measure = [&](const DecodedLevel& l, const ScalarQuantizer& sq, double& worst, long& euler,
                     std::size_t& bad_edges) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
    std::set<std::uint32_t> verts;
    worst = 0;
    for (const auto& t : l.triangles) {
      Vec3 c{0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const Vec3 a = sq.dequantize(l.points[t[k]]), b = sq.dequantize(l.points[t[(k + 1) % 3]]);
        worst = std::max({worst, off_torus(a), off_torus({(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2})});
        for (int ax = 0; ax < 3; ++ax) c[ax] += a[ax] / 3;
        ++edges[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
        verts.insert(t[k]);
      }
      worst = std::max(worst, off_torus(c));
    }
    bad_edges = 0;
    for (const auto& [edge, n] : edges) bad_edges += n != 2;
    euler = static_cast<long>(verts.size()) - static_cast<long>(edges.size()) + static_cast<long>(l.triangles.size());
  };
  for (std::size_t i = 0; i + 1 < e.levels.size(); ++i) {
    CAPTURE(i);
    const DecodedLevel& l = d.value().levels[i];
    CHECK(l.points == e.levels[i].points);
    CHECK(l.triangles == e.levels[i].triangles);
    double worst = 0, worst_plain = 0;
    long euler = 0, euler_plain = 0;
    std::size_t bad = 0, bad_plain = 0;
    measure(l, e.report.quantizer, worst, euler, bad);
    measure(plain.value().levels[i], plain.value().report.quantizer, worst_plain, euler_plain, bad_plain);
    MESSAGE("level ", l.lod, ": ", l.points.size(), " points, off the torus by at most ", worst, " (",
            worst_plain, " without fitting), Euler ", euler, " (", euler_plain, ")");
    CHECK(worst < 0.04);  // about 1 % of the bounding-box diagonal (3.9)
    CHECK(euler == 0);
    CHECK(bad == 0);
    CHECK(l.points.size() < m.points.size());
  }
}

TEST_CASE("preview_ratio: levels of octree cells below the independent-set levels, down to a few percent") {
  const Mesh m = samples::torus(120, 48);  // 5,760 points
  EncodeOptions opt;
  opt.levels = 2;
  opt.preview_ratio = 0.03;
  auto enc = encode(m, opt);
  REQUIRE_MESSAGE(enc.ok(), hmc::testgen::why(enc));
  const Encoded& e = enc.value();
  const int q = e.report.quantizer.bits;
  auto d = decode(e.bytes.data(), e.bytes.size());
  REQUIRE_MESSAGE(d.ok(), hmc::testgen::why(d));
  const auto& levels = d.value().levels;  // coarsest first
  REQUIRE(levels.size() == e.levels.size());
  REQUIRE(levels.size() >= 4);
  const std::size_t n = levels.back().points.size();
  MESSAGE(levels.size(), " levels, the coarsest ", levels.front().points.size(), " of ", n, " points");
  CHECK(static_cast<double>(levels.front().points.size()) <= 0.03 * static_cast<double>(n));
  CHECK(levels.front().points.size() >= 5);
  for (std::size_t i = 0; i < levels.size(); ++i) {
    CAPTURE(i);
    CHECK(levels[i].points == e.levels[i].points);
    CHECK(levels[i].triangles == e.levels[i].triangles);
    CHECK(!levels[i].triangles.empty());
  }
  // Level 0 and 1 come from the independent sets; every coarser level keeps
  // one point per occupied cell of some octree depth D of the next finer
  // level, at most half of its points: the point nearest the cell's centre
  // (first in canonical order on ties).
  for (std::size_t i = 0; i + 2 < levels.size(); ++i) {
    CAPTURE(i);
    const auto& coarse = levels[i].points;
    const auto& finer = levels[i + 1].points;
    CHECK(2 * coarse.size() <= finer.size());
    CHECK(std::includes(finer.begin(), finer.end(), coarse.begin(), coarse.end()));
    int depth = -1;
    for (int dd = 0; dd <= q && depth < 0; ++dd) {
      std::set<std::uint64_t> cells;
      for (const auto& p : finer) cells.insert(morton_key(p, q) >> (3 * (q - dd)));
      if (cells.size() == coarse.size()) depth = dd;
    }
    REQUIRE(depth > 0);
    const int shift = q - depth;
    std::map<std::uint64_t, std::pair<std::int64_t, GridPoint>> nearest;
    for (const auto& p : finer) {
      std::int64_t dist = 0;
      for (int a = 0; a < 3; ++a) {
        const std::int64_t c = ((std::int64_t{p[a]} >> shift) << shift) * 2 + (std::int64_t{1} << shift);
        dist += (2 * std::int64_t{p[a]} - c) * (2 * std::int64_t{p[a]} - c);
      }
      const std::uint64_t cell = morton_key(p, q) >> (3 * shift);
      auto it = nearest.find(cell);
      if (it == nearest.end() || dist < it->second.first) nearest[cell] = {dist, p};
    }
    std::vector<GridPoint> expected;
    for (const auto& [cell, best] : nearest) expected.push_back(best.second);
    std::sort(expected.begin(), expected.end());
    CHECK(expected == coarse);
  }
  opt.preview_ratio = 1;
  CHECK(encode(m, opt).status() == Status::invalid_argument);
  opt.preview_ratio = -0.5;
  CHECK(encode(m, opt).status() == Status::invalid_argument);
}
