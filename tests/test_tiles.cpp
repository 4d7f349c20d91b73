// SPDX-License-Identifier: AGPL-3.0-or-later
// EncodeOptions::lattice (spec/tiles.md): pieces of a model encoded on the
// model's one grid decode to the very grid points, and positions, of the
// untiled stream.
#include <doctest/doctest.h>

#include <algorithm>
#include <set>
#include <vector>

#include "hmc/codec.hpp"
#include "samples.hpp"

using namespace hmc;

namespace {

// The points of `m` whose x is below (or at least) `cut`, with the triangles
// that have all three corners among them.
Mesh half(const Mesh& m, double cut, bool below) {
  Mesh h;
  std::vector<std::uint32_t> local(m.points.size(), UINT32_MAX);
  for (std::size_t i = 0; i < m.points.size(); ++i)
    if ((m.points[i][0] < cut) == below) {
      local[i] = static_cast<std::uint32_t>(h.points.size());
      h.points.push_back(m.points[i]);
    }
  for (const auto& t : m.triangles)
    if (local[t[0]] != UINT32_MAX && local[t[1]] != UINT32_MAX && local[t[2]] != UINT32_MAX)
      h.triangles.push_back({local[t[0]], local[t[1]], local[t[2]]});
  return h;
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
