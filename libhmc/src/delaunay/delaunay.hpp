// SPDX-License-Identifier: AGPL-3.0-or-later
//
// The canonical Delaunay tetrahedralization of a set of grid points
// (spec/delaunay.md). This is the one interface through which the codec
// reaches a Delaunay code; the rest of libhmc never sees the backend.
//
// The result is a function of the point set alone: the Delaunay
// tetrahedralization whose ties (five or more cospherical points, four or
// more coplanar points on the convex hull) are broken by the symbolic
// perturbation of spec/delaunay.md section 3, keyed on each point's index in
// canonical order. Equivalently: the Delaunay subdivision, with each cell
// (a convex polytope inscribed in an empty sphere) triangulated by pulling
// its vertices in canonical order.
//
// Backends. The tetrahedra are computed by TetGen 1.5 (tetgen_backend.cpp,
// the only file that includes tetgen.h), which implements exactly this
// perturbation, when its one floating-point step is provably exact (points
// spanning less than 2^16 grid units on every axis, e.g. every q <= 16);
// otherwise, or should TetGen's output ever fail verification, by the
// built-in exact incremental construction (native_backend.cpp). Whatever
// the backend, delaunay() verifies its output with the exact predicates of
// predicates.hpp before returning it (see certificate_error()), so a backend
// defect can never leak into decoded output: it surfaces as
// Status::internal_error instead.
//
// Cost (informative; one core of the shared 2-core reference machine, 12-bit
// models): TetGen about 0.5-0.7 s per 100k points; the canonical sort,
// adjacency and certificate add 10-30 %. The native backend, with the same
// extras, takes 0.68-0.84 times as long (2026-12-03, medians of 5 alternated
// runs: horse 0.38 against 0.56 s, its 25,272-point coarsest level 0.20
// against 0.24 s, hand_tetgen 0.21 against 0.26 s, Stanford bunny 0.25
// against 0.34 s). TetGen calls are serialized (it keeps global state); the
// native backend is reentrant.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "hmc/codec.hpp"
#include "util/helpers.hpp"

namespace hmc::detail {

/// "No tetrahedron": the neighbour across a convex-hull face.
inline constexpr std::uint32_t kNoTet = 0xFFFFFFFFu;

/// Local face k of a tetrahedron is the face opposite its vertex k. Its
/// vertices, listed by local position in this order, are oriented outward:
/// they appear counter-clockwise seen from outside the tetrahedron, so
/// orient3d(face..., opposite vertex) < 0.
inline constexpr int kFaceVertices[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct Tetrahedralization {
  /// Indices into the input points. Canonical form (spec/delaunay.md §5):
  /// tets[t][0] < tets[t][1] are the two smallest indices of the
  /// tetrahedron; the other two follow in the order that makes
  /// orient3d(p[t0], p[t1], p[t2], p[t3]) > 0. The list is sorted
  /// lexicographically by (t0, t1, t2, t3), without duplicates.
  std::vector<std::array<std::uint32_t, 4>> tets;

  /// neighbors[t][k]: the tetrahedron across local face k of tets[t] (the
  /// face opposite tets[t][k]), or kNoTet when that face lies on the convex
  /// hull. Informative convenience; derived from `tets` alone.
  std::vector<std::array<std::uint32_t, 4>> neighbors;
};

/// The canonical Delaunay tetrahedralization of `points`, which must be
/// distinct grid points (coordinates below 2^21) in canonical order
/// (ascending x, then y, then z); fails with internal_error otherwise.
/// Fewer than 4 points, or all points coplanar: no tetrahedra. Otherwise
/// every point is a vertex of some tetrahedron and the tetrahedra tile the
/// convex hull. Errors (as StreamError): out_of_memory, internal_error, and
/// limit_exceeded (below).
///
/// `max_tets` bounds the work on untrusted points. n points can have up to
/// n(n-3)/2 Delaunay tetrahedra (points on two skew lines come close), so a
/// few kilobytes of stream can ask for billions; TetGen cannot be stopped
/// midway, so it is used only when that worst case is within `max_tets`
/// (always, by default). Otherwise the native backend builds the same
/// canonical tetrahedralization and fails with limit_exceeded as soon as it
/// would need more than max_tets tetrahedra (plus the hull faces).
///
/// `helpers`: where one is free, it takes half of the verification (the
/// same result).
Tetrahedralization delaunay(const std::vector<GridPoint>& points, std::uint64_t max_tets = ~std::uint64_t{0},
                            HelperBudget* helpers = nullptr);

/// The same tetrahedralization as delaunay(points, max_tets), built from
/// that of a subset: `sub` must be delaunay(sub_points) for distinct grid
/// points sub_points, all of them in `points` (both in canonical order).
/// The perturbation depends only on the points' canonical order, which a
/// subset keeps, so inserting the other points into `sub` gives the same
/// result; levels of detail are decoded this way, each from the coarser
/// one, inserting only the points a refinement layer adds. `sub` is
/// consumed (its memory released once copied). Without tetrahedra in `sub`
/// (a flat subset) this is delaunay(points, max_tets). Errors as
/// delaunay(), and internal_error when sub_points is not a subset.
Tetrahedralization delaunay_refine(const std::vector<GridPoint>& points, const std::vector<GridPoint>& sub_points,
                                   Tetrahedralization&& sub, std::uint64_t max_tets = ~std::uint64_t{0},
                                   HelperBudget* helpers = nullptr);

/// n(n-3)/2, the most tetrahedra a Delaunay tetrahedralization of n >= 4
/// points can have (the upper bound theorem applied to the lifted points;
/// saturating).
std::uint64_t max_delaunay_tets(std::uint64_t n);

/// Verifies that `tets` (any vertex order per tetrahedron, any list order)
/// is the canonical Delaunay tetrahedralization of `points` (spec/
/// delaunay.md §6): every tetrahedron positively oriented, every face
/// shared by at most two tetrahedra lying on opposite sides of it, the hull
/// faces a closed, locally convex surface of genus 0, every point a vertex,
/// and every interior face locally Delaunay under the perturbed in-sphere
/// test. Returns an empty string when all checks pass, else a description
/// of the first failure. Linear time.
std::string certificate_error(const std::vector<GridPoint>& points,
                              const std::vector<std::array<std::uint32_t, 4>>& tets);

/// Puts one tetrahedron in canonical vertex order (see Tetrahedralization);
/// returns false if it is flat (orient3d == 0).
bool canonicalize_tet(const std::vector<GridPoint>& points, std::array<std::uint32_t, 4>& tet);

namespace backend {
// Backends fill `tets` (any order, any vertex order) and `neighbors` (same
// order; neighbors[t][k] across the face opposite tets[t][k], kNoTet on the
// hull). delaunay() verifies both before use. Only called with at least 4
// points not all coplanar.

/// TetGen 1.5 (tetgen_backend.cpp). Returns false, without running TetGen,
/// when TetGen cannot be run safely on these points (coordinate extent of
/// 2^16 or more; see there).
bool tetgen(const std::vector<GridPoint>& points, std::vector<std::array<std::uint32_t, 4>>& tets,
            std::vector<std::array<std::uint32_t, 4>>& neighbors);

/// The built-in exact incremental construction (native_backend.cpp). Fails
/// with limit_exceeded, before allocating more, when more than `max_cells`
/// cells (tetrahedra plus convex-hull faces) would be alive at once.
void native(const std::vector<GridPoint>& points, std::vector<std::array<std::uint32_t, 4>>& tets,
            std::vector<std::array<std::uint32_t, 4>>& neighbors, std::uint64_t max_cells = ~std::uint64_t{0});

/// The same construction started from the tetrahedralization of a subset
/// (`sub_tets`, `sub_neighbors`, in the subset's numbering; `index` maps it
/// to `points`), inserting only the other points. Releases the subset's
/// lists once copied; fails with limit_exceeded as native() does.
void native_refine(const std::vector<GridPoint>& points, const std::vector<std::uint32_t>& index,
                   std::vector<std::array<std::uint32_t, 4>>& sub_tets, std::vector<std::array<std::uint32_t, 4>>& sub_neighbors,
                   std::vector<std::array<std::uint32_t, 4>>& tets, std::vector<std::array<std::uint32_t, 4>>& neighbors,
                   std::uint64_t max_cells = ~std::uint64_t{0});
}  // namespace backend

}  // namespace hmc::detail
