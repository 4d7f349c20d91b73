// SPDX-License-Identifier: AGPL-3.0-or-later
// The canonical Delaunay layer (spec/delaunay.md): exact predicates, the
// tie-breaking rule, canonical output, and the library's own certificate,
// all checked against the independent checker in support/.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "delaunay/adjacency.hpp"
#include "delaunay/delaunay.hpp"
#include "delaunay/predicates.hpp"
#include "hmc/codec.hpp"
#include "samples.hpp"
#include "util/error.hpp"
#include "support/delaunay_checker.hpp"

using namespace hmc;
using namespace hmc::detail;
using hmc::check::Tet;

namespace {

std::vector<GridPoint> canonical(std::vector<GridPoint> p) {
  std::sort(p.begin(), p.end());  // std::array compares x, then y, then z
  p.erase(std::unique(p.begin(), p.end()), p.end());
  return p;
}

std::vector<GridPoint> lattice(int nx, int ny, int nz, std::uint32_t h = 1, std::uint32_t offset = 0) {
  std::vector<GridPoint> p;
  for (const auto& v : samples::lattice(nx, ny, nz).points)
    p.push_back({offset + h * static_cast<std::uint32_t>(v[0]), offset + h * static_cast<std::uint32_t>(v[1]),
                 offset + h * static_cast<std::uint32_t>(v[2])});
  return canonical(p);
}

// All integer points of the sphere x^2 + y^2 + z^2 = r^2, scaled by s and
// shifted by r * s so that every coordinate is non-negative.
std::vector<GridPoint> sphere_points(int r, std::uint32_t s = 1) {
  std::vector<GridPoint> p;
  for (int x = -r; x <= r; ++x)
    for (int y = -r; y <= r; ++y)
      for (int z = -r; z <= r; ++z)
        if (x * x + y * y + z * z == r * r)
          p.push_back({static_cast<std::uint32_t>(x + r) * s, static_cast<std::uint32_t>(y + r) * s,
                       static_cast<std::uint32_t>(z + r) * s});
  return canonical(p);
}

std::vector<GridPoint> quantize(const Mesh& m, int q) {
  EncodeOptions o;
  o.bits = q;
  auto e = encode(m, o);
  REQUIRE(e.ok());
  return e.value().points;
}

// Runs delaunay() and the independent checker; returns the result.
Tetrahedralization run(const std::vector<GridPoint>& p, bool plane_check = true) {
  Tetrahedralization t = delaunay(p);
  const auto rep = check::check_delaunay(p, t.tets, plane_check);
  INFO("points: " << p.size() << ", tets: " << t.tets.size());
  CHECK_MESSAGE(rep.ok, rep.error);
  CHECK(certificate_error(p, t.tets).empty());
  // The native backend agrees (delaunay() uses TetGen where it may).
  if (!t.tets.empty()) {
    std::vector<Tet> other, other_nb;
    backend::native(p, other, other_nb);
    for (auto& T : other) CHECK(canonicalize_tet(p, T));
    std::sort(other.begin(), other.end());
    CHECK(other == t.tets);
  }
  // The neighbours are the face adjacency.
  REQUIRE(t.neighbors.size() == t.tets.size());
  for (std::size_t i = 0; i < t.tets.size(); ++i)
    for (int k = 0; k < 4; ++k) {
      const auto u = t.neighbors[i][k];
      if (u == kNoTet) continue;
      int shared = 0;
      for (auto v : t.tets[u]) shared += std::count(t.tets[i].begin(), t.tets[i].end(), v) ? 1 : 0;
      CHECK(shared == 3);
      CHECK(std::count(t.tets[u].begin(), t.tets[u].end(), t.tets[i][k]) == 0);
    }
  return t;
}

}  // namespace

TEST_CASE("predicates: conventions") {
  const GridPoint o{0, 0, 0}, x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
  CHECK(orient3d(o, x, y, z) == 1);
  CHECK(orient3d(x, o, y, z) == -1);
  CHECK(orient3d(o, x, y, GridPoint{5, 7, 0}) == 0);
  const GridPoint a{0, 0, 0}, b{4, 0, 0}, c{0, 4, 0}, d{0, 0, 4};
  CHECK(insphere(a, b, c, d, GridPoint{1, 1, 1}) == 1);
  CHECK(insphere(a, b, c, d, GridPoint{9, 9, 9}) == -1);
  CHECK(insphere(a, b, c, d, GridPoint{4, 4, 0}) == 0);  // on the sphere through the cube's corners
  // The checker agrees on the conventions.
  CHECK(check::vol6(check::to_pt(a), check::to_pt(b), check::to_pt(c), check::to_pt(d)) > 0);
  CHECK(check::lifted({check::to_pt(a), check::to_pt(b), check::to_pt(c), check::to_pt(d), {1, 1, 1}}) < 0);
}

TEST_CASE("predicates: exact at the 2^21 bit budget, and equal to the checker's") {
  std::mt19937_64 rng(7);
  const std::uint32_t hi = (1u << 21) - 1;
  auto coord = [&](int mode) -> std::uint32_t {
    switch (mode) {
      case 0: return static_cast<std::uint32_t>(rng() % (hi + 1));            // anywhere
      case 1: return (rng() & 1) ? hi : 0;                                     // extremes
      case 2: return static_cast<std::uint32_t>(rng() % 3) * (hi / 2);        // coarse grid: many ties
      default: return hi - static_cast<std::uint32_t>(rng() % 3);             // near the top
    }
  };
  int ties = 0;
  for (int it = 0; it < 3000; ++it) {
    const int mode = it % 4;
    std::vector<GridPoint> p(5);
    for (auto& q : p) q = {coord(mode), coord(mode), coord(mode)};
    std::array<check::Pt, 5> c;
    for (int i = 0; i < 5; ++i) c[i] = check::to_pt(p[i]);
    CHECK(orient3d(p[0], p[1], p[2], p[3]) == check::sgn(check::vol6(c[0], c[1], c[2], c[3])));
    const int s = insphere(p[0], p[1], p[2], p[3], p[4]);
    CHECK(s == -check::sgn(check::lifted(c)));
    ties += s == 0;
    // Perturbed: ranks = positions in this 5-point array.
    CHECK(insphere_perturbed(p, {0, 1, 2, 3, 4}) == -check::lifted_perturbed(c, {0, 1, 2, 3, 4}));
    CHECK(insphere_perturbed(p, {3, 0, 4, 2, 1}) ==
          -check::lifted_perturbed({c[3], c[0], c[4], c[2], c[1]}, {3, 0, 4, 2, 1}));
  }
  CHECK(ties > 100);
}

TEST_CASE("perturbed insphere: worked example of the spec") {
  // Unit cube, canonical order: index = 4x + 2y + z. All eight are cospherical.
  const auto cube = lattice(2, 2, 2);
  REQUIRE(cube.size() == 8);
  for (std::uint32_t e = 0; e < 8; ++e) CHECK(insphere(cube[0], cube[1], cube[2], cube[4], cube[e]) == 0);
    // spec §3.3: is point 3 inside the perturbed sphere of (0, 1, 5, 7)?
  CHECK(orient3d(cube[0], cube[1], cube[5], cube[7]) == 1);
  CHECK(insphere(cube[0], cube[1], cube[5], cube[7], cube[3]) == 0);       // a tie
  CHECK(orient3d(cube[1], cube[5], cube[7], cube[3]) == 0);                // index 0, r = 0: no decision
  CHECK(orient3d_value(cube[0], cube[5], cube[7], cube[3]) == 1);         // index 1, r = 1: -(+1)
  CHECK(insphere_perturbed(cube, {0, 1, 5, 7, 3}) == -1);                  // outside
  const auto t = run(cube);
  CHECK(t.tets.size() == 6);
  for (const auto& T : t.tets) CHECK(T[0] == 0);  // pulled from vertex 0
  const std::vector<Tet> expected = {{0, 1, 5, 7}, {0, 1, 7, 3}, {0, 2, 3, 7}, {0, 2, 7, 6}, {0, 4, 6, 7}, {0, 4, 7, 5}};
  CHECK(t.tets == expected);
}

TEST_CASE("degenerate inputs give no tetrahedra") {
  CHECK(delaunay({}).tets.empty());
  CHECK(delaunay({{1, 2, 3}}).tets.empty());
  CHECK(delaunay({{1, 2, 3}, {1, 2, 4}}).tets.empty());
  CHECK(delaunay({{0, 0, 0}, {0, 1, 0}, {1, 0, 0}}).tets.empty());
  CHECK(delaunay({{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}}).tets.empty());
  CHECK(delaunay(lattice(1, 6, 7)).tets.empty());
  CHECK(delaunay(lattice(9, 1, 1)).tets.empty());
  for (int q : {8, 12, 16}) {
    const auto cop = quantize(samples::coplanar(400, 3), q);
    const auto col = quantize(samples::collinear(400, 4), q);
    // Quantization may move points off the exact plane/line; the checker
    // decides what the right answer is.
    const auto a = delaunay(cop), b = delaunay(col);
    CHECK(a.tets.empty() == !check::spans_3d(cop));
    CHECK(b.tets.empty() == !check::spans_3d(col));
    if (!a.tets.empty()) run(cop);
  }
  // Exactly coplanar and collinear sets at full precision.
  std::mt19937_64 rng(11);
  std::vector<GridPoint> plane, line;
  for (int i = 0; i < 300; ++i) {
    const std::uint32_t u = static_cast<std::uint32_t>(rng() % 1000), v = static_cast<std::uint32_t>(rng() % 1000);
    plane.push_back({u + v, 2 * u + 1000, 3000 - v});
    line.push_back({7 * u, 3 * u + 5, 100000 - 11 * u});
  }
  CHECK(delaunay(canonical(plane)).tets.empty());
  CHECK(delaunay(canonical(line)).tets.empty());
  // Smallest non-degenerate sets.
  const auto one = run({{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 0, 0}});
  CHECK(one.tets == std::vector<Tet>{{0, 1, 3, 2}});
  run({{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {1, 1, 1}});
  // Coplanar points plus one apex: a pyramid over a 5x5 lattice square.
  auto pyramid = lattice(5, 5, 1);
  pyramid.push_back({2, 2, 3});
  run(canonical(pyramid));
}

TEST_CASE("rejects inputs that break the precondition") {
  CHECK_THROWS_AS(delaunay({{0, 0, 1}, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}}), StreamError);  // not sorted
  CHECK_THROWS_AS(delaunay({{0, 0, 0}, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}}), StreamError);  // duplicate
  CHECK_THROWS_AS(delaunay({{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1u << 21, 0, 0}}), StreamError);
}

TEST_CASE("agrees with the brute-force definition on small degenerate sets") {
  std::mt19937_64 rng(2024);
  int compared = 0, tie_sets = 0;
  const auto cube3 = lattice(3, 3, 3);
  const auto sph = sphere_points(3);  // 30 points on x^2+y^2+z^2 = 9
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<GridPoint> p;
    const std::size_t n = 5 + rng() % 8;  // 5..12 points
    const int source = trial % 4;
    while (p.size() < n) {
      if (source == 0) p.push_back(cube3[rng() % cube3.size()]);
      else if (source == 1) p.push_back(sph[rng() % sph.size()]);
      else if (source == 2)
        p.push_back({static_cast<std::uint32_t>(rng() % 4), static_cast<std::uint32_t>(rng() % 4),
                     static_cast<std::uint32_t>(rng() % 4)});
      else  // a flat 4x4 face plus a few points off it: coplanar hull facets
        p.push_back({static_cast<std::uint32_t>(rng() % 4), static_cast<std::uint32_t>(rng() % 4),
                     p.size() < n - 2 ? 0u : static_cast<std::uint32_t>(1 + rng() % 3)});
      p = canonical(p);
    }
    const auto expected = check::brute_force(p);
    if (expected.empty()) {
      CHECK(delaunay(p).tets.empty());
      continue;
    }
    const auto t = delaunay(p);
    INFO("trial " << trial << ", n = " << p.size());
    CHECK(t.tets == expected);
    std::vector<Tet> nat, nat_nb;
    backend::native(p, nat, nat_nb);
    for (auto& T : nat) CHECK(canonicalize_tet(p, T));
    std::sort(nat.begin(), nat.end());
    CHECK(nat == expected);
    const auto rep = check::check_delaunay(p, t.tets);
    CHECK_MESSAGE(rep.ok, rep.error);
    tie_sets += rep.cospherical_faces > 0;
    ++compared;
  }
  CHECK(compared > 300);
  CHECK(tie_sets > 200);
}

TEST_CASE("lattices") {
  const int dims[][3] = {{2, 2, 2}, {3, 3, 3}, {4, 4, 4}, {5, 5, 5}, {6, 6, 6}, {7, 7, 7}, {8, 8, 8},
                         {5, 3, 7}, {2, 9, 4}, {2, 2, 11}, {6, 2, 3}};
  for (const auto& d : dims) {
    const auto p = lattice(d[0], d[1], d[2]);
    const auto t = run(p);
    // A lattice is all ties: every tetrahedron has a cospherical face.
    const auto rep = check::check_delaunay(p, t.tets, false);
    CHECK(rep.tie_tets == t.tets.size());
    std::uint64_t vol = 0;
    for (const auto& T : t.tets)
      vol += static_cast<std::uint64_t>(orient3d_value(p[T[0]], p[T[1]], p[T[2]], p[T[3]]));
    CHECK(vol == 6ull * static_cast<std::uint64_t>((d[0] - 1) * (d[1] - 1) * (d[2] - 1)));
  }
  // At the top of the coordinate range: spacing 2^20 - 1, and 3 points per
  // axis reaching 2^21 - 2.
  run(lattice(3, 3, 3, (1u << 20) - 1));
  run(lattice(4, 3, 2, 699050, 1));
}

TEST_CASE("cospherical sets") {
  for (int r : {5, 13, 25}) {
    const auto p = sphere_points(r);
    INFO("r = " << r << ", " << p.size() << " points");
    const auto t = run(p);
    const auto rep = check::check_delaunay(p, t.tets, false);
    CHECK(rep.cospherical_faces == rep.interior_faces);
  }
  // Scaled to the top of the range: coordinates up to 50 * 41943 = 2^21 - 2.
  run(sphere_points(25, 41943), false);
  // Sphere plus its centre: every tet has the centre as a vertex.
  auto p = sphere_points(13);
  p.push_back({13, 13, 13});
  p = canonical(p);
  const auto t = run(p);
  const auto centre = static_cast<std::uint32_t>(std::find(p.begin(), p.end(), GridPoint{13, 13, 13}) - p.begin());
  for (const auto& T : t.tets) CHECK(std::count(T.begin(), T.end(), centre) == 1);
}

TEST_CASE("quantized random balls and generated surfaces") {
  for (int q : {8, 10, 12, 14}) {
    INFO("q = " << q);
    run(quantize(samples::random_ball(1500, 100 + static_cast<std::uint64_t>(q)), q));
    run(quantize(samples::torus(48, 20), q));
    run(quantize(samples::uv_sphere(24, 40), q));
    run(quantize(samples::random_sphere_points(1000, 5), q));
  }
  run(quantize(samples::clustered(6, 120, 9), 12));
  run(quantize(samples::clustered(3, 200, 10), 6));
}

TEST_CASE("the output is a function of the point set") {
  std::mt19937_64 rng(99);
  std::vector<std::vector<GridPoint>> sets = {lattice(4, 5, 3), sphere_points(13),
                                              quantize(samples::torus(40, 16), 10),
                                              quantize(samples::random_ball(800, 3), 8)};
  for (const auto& p : sets) {
    const auto t = delaunay(p);
    auto shuffled = p;
    for (int k = 0; k < 3; ++k) {
      std::shuffle(shuffled.begin(), shuffled.end(), rng);
      CHECK(delaunay(canonical(shuffled)).tets == t.tets);
    }
    // Translation by a grid vector keeps the tetrahedra (same order, same
    // geometry), as the rule depends on positions only through predicates.
    auto moved = p;
    for (auto& g : moved) g = {g[0] + 1000, g[1] + 17, g[2] + 123456};
    CHECK(delaunay(moved).tets == t.tets);
  }
}

TEST_CASE("the certificate rejects a valid but non-canonical tetrahedralization") {
  // The cube pulled from vertex 1 instead of 0: a valid tiling, other ties.
  const auto cube = lattice(2, 2, 2);
  const auto canon = delaunay(cube).tets;
  // Cones from 1 = (0,0,1) over the faces without it, x = 1 {4,5,6,7},
  // y = 1 {2,3,6,7} and z = 0 {0,2,4,6}, each pulled from its first vertex.
  std::vector<Tet> other = {{1, 4, 5, 7}, {1, 4, 7, 6}, {1, 2, 3, 7}, {1, 2, 7, 6}, {1, 0, 2, 6}, {1, 0, 6, 4}};
  for (auto& T : other) CHECK(canonicalize_tet(cube, T));
  std::sort(other.begin(), other.end());
  CHECK(other != canon);
  const auto rep = check::check_delaunay(cube, other);
  CHECK(!rep.ok);
  CHECK(rep.error.find("locally Delaunay") != std::string::npos);
  CHECK(!certificate_error(cube, other).empty());
  // Dropping or duplicating a tetrahedron is caught too.
  auto missing = canon;
  missing.pop_back();
  CHECK(!certificate_error(cube, missing).empty());
  CHECK(!check::check_delaunay(cube, missing).ok);
  auto twice = canon;
  twice.push_back(canon[0]);
  std::sort(twice.begin(), twice.end());
  CHECK(!certificate_error(cube, twice).empty());
  CHECK(!check::check_delaunay(cube, twice).ok);
}

TEST_CASE("adjacency and hull faces") {
  const auto p = lattice(4, 4, 4);
  const auto t = delaunay(p);
  std::vector<std::array<std::uint32_t, 4>> nb;
  REQUIRE(build_adjacency(t.tets, p.size(), nb));
  CHECK(nb == t.neighbors);
  const auto hull = hull_faces(t.tets, nb);
  CHECK(hull.size() == 6u * 9u * 2u);  // each 3x3-cell face of the cube: 18 triangles
  for (const auto& f : hull) {
    const auto& T = t.tets[f.tet];
    CHECK(orient3d(p[f.v[0]], p[f.v[1]], p[f.v[2]], p[T[static_cast<std::size_t>(f.local_face)]]) < 0);
  }
}

TEST_CASE("TetGen and the native backend build the same tetrahedra") {
  // Two independent constructions, one rule: TetGen's insertion order (BRIO
  // with Hilbert curves, randomised) and the native one (BRIO with Morton
  // curves, another seed) differ, the ties they meet differ, the result
  // does not.
  const std::vector<std::vector<GridPoint>> sets = {
      lattice(6, 5, 4), lattice(8, 8, 8), sphere_points(13), sphere_points(25), lattice(3, 3, 3, 21845, 7),
      quantize(samples::torus(40, 16), 9), quantize(samples::random_ball(2000, 8), 7),
      quantize(samples::uv_sphere(20, 30), 12), quantize(samples::clustered(4, 100, 3), 10)};
  for (const auto& p : sets) {
    std::vector<Tet> a, an, b, bn;
    REQUIRE(backend::tetgen(p, a, an));
    backend::native(p, b, bn);
    CHECK(certificate_error(p, a).empty());
    CHECK(certificate_error(p, b).empty());
    for (auto* v : {&a, &b}) {
      for (auto& T : *v) CHECK(canonicalize_tet(p, T));
      std::sort(v->begin(), v->end());
    }
    CHECK(a == b);
    CHECK(a == delaunay(p).tets);
  }
}

TEST_CASE("a tetrahedra budget stops quadratic tetrahedralizations early") {
  // n points on two skew lines: (n/2 - 1)^2 tetrahedra.
  std::vector<GridPoint> p;
  for (std::uint32_t i = 0; i < 200; ++i) p.push_back({10 * i, 0, 0});
  for (std::uint32_t j = 0; j < 200; ++j) p.push_back({0, 10 * j, 5000});
  p = canonical(p);
  CHECK(max_delaunay_tets(4) == 2);
  CHECK(max_delaunay_tets(400) == 400 * 397 / 2);
  CHECK(max_delaunay_tets(std::uint64_t{1} << 40) == ~std::uint64_t{0});
  const auto full = delaunay(p);  // unlimited: TetGen
  CHECK(full.tets.size() == 199 * 199);
  // A budget under TetGen's worst case but above the real size: the native
  // backend, same tetrahedra.
  CHECK(delaunay(p, 50000).tets == full.tets);
  try {
    (void)delaunay(p, 20000);
    FAIL("no limit_exceeded");
  } catch (const StreamError& e) {
    CHECK(e.error().status == Status::limit_exceeded);
  }
  // The same budget holds when the tetrahedra are refined from a subset's.
  std::vector<GridPoint> half;
  for (std::size_t i = 0; i < p.size(); i += 2) half.push_back(p[i]);
  CHECK(delaunay_refine(p, half, delaunay(half), 50000).tets == full.tets);
  try {
    (void)delaunay_refine(p, half, delaunay(half), 20000);
    FAIL("no limit_exceeded");
  } catch (const StreamError& e) {
    CHECK(e.error().status == Status::limit_exceeded);
  }
  // Ordinary sets are not affected by a budget a few times their size.
  const auto ball = quantize(samples::random_ball(3000, 8), 10);
  const auto t = delaunay(ball);
  CHECK(delaunay(ball, 4 * t.tets.size()).tets == t.tets);
}

TEST_CASE("large coordinates: the native backend, and no TetGen hazards") {
  // TetGen is not run when a coordinate extent reaches 2^16 (its first
  // tetrahedron is chosen in floating point); delaunay() still answers.
  std::vector<Tet> t, n;
  CHECK(!backend::tetgen(lattice(3, 3, 3, 1u << 15), t, n));
  CHECK(backend::tetgen(lattice(3, 3, 3, (1u << 15) - 1), t, n));
  run(lattice(5, 4, 3, 400000, 3));
  run(quantize(samples::random_ball(3000, 21), 21));
  run(quantize(samples::torus(60, 24), 19));
  // Nearly flat sets spanning the whole range: a tilted plane x + y + z = C
  // and one point off it by one unit. (These made TetGen abort.)
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<GridPoint> p;
    const std::uint32_t C = 3u << 20;
    while (p.size() < 600) {
      const auto a = static_cast<std::uint32_t>(rng() % (1u << 21)), b = static_cast<std::uint32_t>(rng() % (1u << 21));
      if (a + b > C || C - a - b >= (1u << 21)) continue;
      p.push_back({a, b, C - a - b});
    }
    p.push_back({700000, 700000, C - 1400000 + 1});
    run(canonical(p));
  }
}

// Levels of detail are decoded by refining the coarser level's
// tetrahedralization (delaunay_refine): the result must be delaunay() of
// the finer set exactly, ties included, whatever the subset.
TEST_CASE("delaunay_refine equals delaunay of the whole set") {
  std::mt19937_64 rng(11);
  auto subset = [&](const std::vector<GridPoint>& p, double keep) {
    std::bernoulli_distribution b(keep);
    std::vector<GridPoint> s;
    for (const auto& x : p)
      if (b(rng)) s.push_back(x);
    return s;
  };
  auto random_points = [&](std::size_t n, std::uint32_t extent) {
    std::uniform_int_distribution<std::uint32_t> u(0, extent - 1);
    std::vector<GridPoint> p;
    for (std::size_t i = 0; i < n; ++i) p.push_back({u(rng), u(rng), u(rng)});
    return canonical(p);
  };
  struct Case {
    const char* name;
    std::vector<GridPoint> points;
  };
  const Case cases[] = {
      {"random", random_points(3000, 4096)},
      {"random, small grid (many ties)", random_points(800, 12)},
      {"lattice (every cell cospherical)", lattice(9, 8, 7)},
      {"integer sphere", sphere_points(9)},
  };
  for (const Case& c : cases) {
    for (double keep : {0.9, 0.5, 0.1}) {
      INFO(c.name << ", keeping " << keep);
      const auto sub = subset(c.points, keep);
      Tetrahedralization coarse = delaunay(sub);
      REQUIRE(!coarse.tets.empty());
      const Tetrahedralization whole = delaunay(c.points);
      const Tetrahedralization refined = delaunay_refine(c.points, sub, std::move(coarse));
      CHECK(refined.tets == whole.tets);
      CHECK(refined.neighbors == whole.neighbors);
    }
  }
  // Points added outside the subset's hull, and a subset that is the whole set.
  const auto ball = random_points(2000, 1000);
  std::vector<GridPoint> inner;
  for (const auto& p : ball)
    if (p[0] > 300 && p[0] < 700 && p[1] > 300 && p[1] < 700 && p[2] > 300 && p[2] < 700) inner.push_back(p);
  CHECK(delaunay_refine(ball, inner, delaunay(inner)).tets == delaunay(ball).tets);
  CHECK(delaunay_refine(ball, ball, delaunay(ball)).tets == delaunay(ball).tets);
  // A flat subset has no tetrahedra: the whole set is built from scratch.
  const auto cube = lattice(4, 4, 4);
  std::vector<GridPoint> flat;
  for (const auto& p : cube)
    if (p[2] == 0) flat.push_back(p);
  Tetrahedralization none = delaunay(flat);
  CHECK(none.tets.empty());
  CHECK(delaunay_refine(cube, flat, std::move(none)).tets == delaunay(cube).tets);
  // Points that are not a subset are a caller's bug.
  std::vector<GridPoint> stranger = inner;
  stranger.push_back({1001, 1001, 1001});
  CHECK_THROWS_AS(delaunay_refine(ball, stranger, delaunay(stranger)), StreamError);
}
