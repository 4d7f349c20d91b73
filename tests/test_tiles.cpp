// SPDX-License-Identifier: AGPL-3.0-or-later
// EncodeOptions::lattice (spec/tiles.md): pieces of a model encoded on the
// model's one grid decode to the very grid points, and positions, of the
// untiled stream.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <random>
#include <set>
#include <vector>

#include "hmc/codec.hpp"
#include "samples.hpp"

using namespace hmc;

namespace {

// The points of `m` that `keep` accepts, with the triangles that have all
// three corners among them.
template <class Keep>
Mesh piece(const Mesh& m, Keep keep) {
  Mesh h;
  std::vector<std::uint32_t> local(m.points.size(), UINT32_MAX);
  for (std::size_t i = 0; i < m.points.size(); ++i)
    if (keep(m.points[i])) {
      local[i] = static_cast<std::uint32_t>(h.points.size());
      h.points.push_back(m.points[i]);
    }
  for (const auto& t : m.triangles)
    if (local[t[0]] != UINT32_MAX && local[t[1]] != UINT32_MAX && local[t[2]] != UINT32_MAX)
      h.triangles.push_back({local[t[0]], local[t[1]], local[t[2]]});
  return h;
}

// The points of `m` whose x is below (or at least) `cut`, with their triangles.
Mesh half(const Mesh& m, double cut, bool below) {
  return piece(m, [&](const Vec3& p) { return (p[0] < cut) == below; });
}

}  // namespace

TEST_CASE("two tiles encoded on the untiled stream's lattice decode to its grid points and positions") {
  const Mesh torus = samples::torus(60, 30);
  EncodeOptions whole_opt;
  whole_opt.bits = 11;
  auto whole = encode(torus, whole_opt);
  REQUIRE(whole.ok());
  const ScalarQuantizer& gq = whole.value().report.quantizer;
  auto whole_dec = decode(whole.value().bytes.data(), whole.value().bytes.size());
  REQUIRE(whole_dec.ok());
  const auto& expected = whole_dec.value().finest().points;

  const double cut = 0.3;  // off-centre, so the two tiles' own bounding boxes differ from the model's
  std::vector<GridPoint> merged;
  for (bool below : {true, false}) {
    const Mesh tile = half(torus, cut, below);
    REQUIRE(!tile.points.empty());
    EncodeOptions opt = whole_opt;
    opt.lattice = EncodeOptions::Lattice{gq.origin, gq.step};
    auto enc = encode(tile, opt);
    REQUIRE(enc.ok());
    auto dec = decode(enc.value().bytes.data(), enc.value().bytes.size());
    REQUIRE(dec.ok());
    CHECK(dec.value().quantizer.bits == gq.bits);
    CHECK(dec.value().quantizer.step == gq.step);
    CHECK(dec.value().quantizer.origin == gq.origin);
    for (const auto& p : dec.value().finest().points) {
      merged.push_back(p);
      CHECK(dec.value().quantizer.dequantize(p) == gq.dequantize(p));
    }
    // Without the lattice, the upper tile gets its own grid (its box starts at x >= cut).
    auto own = encode(tile, whole_opt);
    REQUIRE(own.ok());
    if (!below) CHECK(own.value().report.quantizer.origin != gq.origin);
  }
  std::sort(merged.begin(), merged.end());
  CHECK(std::adjacent_find(merged.begin(), merged.end()) == merged.end());  // the halves are disjoint
  CHECK(merged == expected);
}

TEST_CASE("a lattice that does not hold every point, or is not a grid, is refused") {
  const Mesh torus = samples::torus(20, 10);
  auto whole = encode(torus, {});
  REQUIRE(whole.ok());
  const ScalarQuantizer& gq = whole.value().report.quantizer;
  EncodeOptions opt;
  opt.lattice = EncodeOptions::Lattice{gq.origin, gq.step / 2};  // half the step: the far half falls off the grid
  auto r = encode(torus, opt);
  REQUIRE(!r.ok());
  CHECK(r.error().status == Status::invalid_argument);
  CHECK(r.error().message.find("outside the given lattice") != std::string::npos);
  opt.lattice = EncodeOptions::Lattice{gq.origin, 0.0};
  CHECK(!encode(torus, opt).ok());
  opt.lattice = EncodeOptions::Lattice{gq.origin, gq.step};
  CHECK(encode(torus, opt).ok());
}

TEST_CASE("a tile measures its tolerances against the whole model (EncodeOptions::tolerance_diagonal)") {
  // An open, wavy height field with noise of about half an edge, cut
  // to x, y < 0.3 with a margin of 4 edges: the tile's piece, encoded exactly
  // on the model's lattice with its box as the seal, keeps the untiled
  // stream's triangles in its box only when its drop list's tolerance is
  // the whole model's (1/1000 of its diagonal); with its own smaller box it
  // drops faces the untiled stream keeps (40 here; a 58,382-point noisy
  // field in 4 tiles lost 1,876 triangles so).
  const int n = 90;
  Mesh field;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0, 0.006);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = double(i) / (n - 1), y = double(j) / (n - 1);
      field.points.push_back({x, y, 0.08 * std::sin(6.1 * x + 1) * std::cos(4.3 * y) + 0.05 * std::sin(13 * x * y) + noise(rng)});
    }
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      const auto a = std::uint32_t(i * n + j), b = std::uint32_t((i + 1) * n + j), c = b + 1, d = a + 1;
      field.triangles.push_back({a, b, c});
      field.triangles.push_back({a, c, d});
    }
  EncodeOptions whole_opt;
  whole_opt.bits = 14;
  whole_opt.fidelity = Fidelity::exact;
  whole_opt.levels = 1;
  auto whole = encode(field, whole_opt);
  REQUIRE(whole.ok());
  const ScalarQuantizer& gq = whole.value().report.quantizer;
  auto whole_dec = decode(whole.value().bytes.data(), whole.value().bytes.size());
  REQUIRE(whole_dec.ok());
  const DecodedLevel& w = whole_dec.value().finest();
  double diagonal = 0;
  for (int ax = 0; ax < 3; ++ax) {
    std::uint32_t lo = UINT32_MAX, hi = 0;
    for (const auto& p : w.points) lo = std::min(lo, p[ax]), hi = std::max(hi, p[ax]);
    diagonal += double(hi - lo) * double(hi - lo);
  }
  diagonal = std::sqrt(diagonal);

  // Lattice coordinates of the cut; the tile owns x and y below it, its
  // input reaches 4 edges beyond.
  const double cut = 0.3, margin = 4.0 / (n - 1);
  const auto box_x = static_cast<std::uint32_t>(std::ceil((cut - gq.origin[0]) / gq.step));
  const auto box_y = static_cast<std::uint32_t>(std::ceil((cut - gq.origin[1]) / gq.step));
  const Mesh tile = piece(field, [&](const Vec3& p) { return p[0] < cut + margin && p[1] < cut + margin; });
  // Triangles as their corners' grid points, kept where the tile keeps them
  // (first corner in canonical order inside the box).
  using Corners = std::array<GridPoint, 3>;
  auto kept = [&](const DecodedLevel& l) {
    std::set<Corners> out;
    for (const auto& t : l.triangles) {
      Corners c{l.points[t[0]], l.points[t[1]], l.points[t[2]]};
      std::sort(c.begin(), c.end());
      if (c[0][0] < box_x && c[0][1] < box_y) out.insert(c);
    }
    return out;
  };
  const auto expected = kept(w);
  REQUIRE(expected.size() > 1000);
  std::size_t differ[2] = {0, 0};  // with the model's diagonal, with the tile's own
  for (int own = 0; own < 2; ++own) {
    EncodeOptions opt = whole_opt;
    opt.lattice = EncodeOptions::Lattice{gq.origin, gq.step};
    opt.seal_box = std::array<std::uint32_t, 6>{0, 0, 0, box_x, box_y, 1u << 14};
    opt.tolerance_diagonal = own ? 0.0 : diagonal;
    auto enc = encode(tile, opt);
    REQUIRE(enc.ok());
    auto dec = decode(enc.value().bytes.data(), enc.value().bytes.size());
    REQUIRE(dec.ok());
    const auto got = kept(dec.value().finest());
    std::vector<Corners> sym;
    std::set_symmetric_difference(got.begin(), got.end(), expected.begin(), expected.end(), std::back_inserter(sym));
    differ[own] = sym.size();
  }
  MESSAGE("triangles in the box unlike the untiled stream's: " << differ[0] << " with the model's diagonal, "
                                                                << differ[1] << " with the tile's own");
  CHECK(differ[0] == 0);
  CHECK(differ[1] > 10);

  EncodeOptions bad = whole_opt;
  for (double d : {-1.0, std::nan(""), HUGE_VAL}) {
    bad.tolerance_diagonal = d;
    auto r = encode(field, bad);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().status == Status::invalid_argument);
  }
}
