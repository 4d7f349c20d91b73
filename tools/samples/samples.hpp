// SPDX-License-Identifier: AGPL-3.0-or-later
// Generated sample inputs: the tests build their data from these (nothing is
// read from outside the repository), and `hmc gen` writes them for users,
// the quick start and the benchmarks.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "hmc/mesh.hpp"

namespace hmc::samples {

/// Deterministic random source for tests.
using Rng = std::mt19937_64;

/// Triangulated UV sphere (closed surface) with `rings` x `segments` quads.
Mesh uv_sphere(int rings, int segments, double radius = 1.0);
/// Triangulated torus (closed, genus 1) on a `nu` x `nv` grid.
Mesh torus(int nu, int nv, double major = 1.0, double minor = 0.35);
/// An open surface: a height field z = amplitude·sin(5u + 1)·cos(4v − 0.5)
/// over a jittered n x n grid of the unit square, turned by 0.4 rad about z
/// (so its border points are not in canonical order along the outline).
/// Its border is the square's outline.
Mesh height_field(int n, double amplitude);
/// Points uniformly distributed inside a ball (no connectivity).
Mesh random_ball(std::size_t n, std::uint64_t seed, double radius = 1.0);
/// A ball sampled on concentric shells, outermost first: counts[0] points
/// on the unit sphere, counts[1] on the sphere of radius (n-1)/n, ... (n =
/// number of shells); a shell of one point is the centre. Fibonacci
/// spirals, so the sampling is even and deterministic. No connectivity.
Mesh layered_ball(const std::vector<int>& counts);
/// Points uniformly distributed on a sphere surface (no connectivity).
Mesh random_sphere_points(std::size_t n, std::uint64_t seed, double radius = 1.0);
/// Integer lattice nx*ny*nz with spacing `h` (many cospherical points).
Mesh lattice(int nx, int ny, int nz, double h = 1.0);
/// Gaussian clusters: `clusters` centres, `per` points each.
Mesh clustered(int clusters, int per, std::uint64_t seed);
/// Random points on the plane z = 0.3x - 0.2y + 1.
Mesh coplanar(std::size_t n, std::uint64_t seed);
/// Random points on a line.
Mesh collinear(std::size_t n, std::uint64_t seed);
/// `n` copies of the same point.
Mesh all_duplicates(std::size_t n);

}  // namespace hmc::samples
