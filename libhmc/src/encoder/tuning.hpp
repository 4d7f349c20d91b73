// SPDX-License-Identifier: AGPL-3.0-or-later
// Encoder side of reconstruction (non-normative): what the input says each
// Delaunay tetrahedron should be (inside or outside), and the side
// information that makes the normative rule reproduce it at least cost.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "delaunay/delaunay.hpp"
#include "hmc/codec.hpp"
#include "reconstruct/reconstruct.hpp"
#include "util/helpers.hpp"

namespace hmc::detail {

class WindingNumber;
class ClosedSurface;

/// The input's connectivity on the quantization grid: indices into the
/// level's canonical points. Degenerate elements (merged vertices) dropped.
struct GridMesh {
  std::vector<Triangle> triangles;
  std::vector<Tetrahedron> tetrahedra;
};

/// Inside/outside label of every tetrahedron of `dt` according to the input:
/// the generalized winding number of its centroid with respect to the input
/// surface (for volumes, the boundary of the input tetrahedra), with flat
/// tetrahedra on the surface settled by which of their faces are input
/// faces. `surface` is evaluated at `surface_points` (grid units), which may
/// be a finer level's points than the tetrahedralized ones.
///
/// With integer surface points (ClosedSurface::exact) the winding number
/// is that of the surface closed by caps, counted exactly from one
/// tetrahedron's centroid to the next, less the caps' own (ClosedSurface);
/// the sum over the surface's triangles (WindingNumber) is only taken at
/// centroids that lie on a triangle. On the shared models at q = 12 (1 and
/// 4 levels) the streams are those of the sum at every centroid, except
/// the open Stanford bunny's (2 bytes more: the caps' sum is approximate
/// too, and near the holes a label can turn).
///
/// `cache`, when given, carries the structures built for the surface from
/// one call to the next with the same `surface_points` and `surface`
/// objects (they refer to the points, which must outlive the cache).
struct WindingCache {
  const std::vector<Vec3>* points = nullptr;
  const std::vector<Triangle>* surface = nullptr;
  std::shared_ptr<const ClosedSurface> closed;  ///< when the points are exact
  std::shared_ptr<const WindingNumber> tree;    ///< the surface's, once needed
  std::shared_ptr<const WindingNumber> caps;    ///< the caps', when there are caps
  /// Helper threads (EncodeOptions::threads): with one free, the caps'
  /// winding numbers are computed in two halves at once; the values are the
  /// same.
  HelperBudget* helpers = nullptr;
};
/// truth_labels(), described above WindingCache. `sheet`: read the surface as an open sheet, whose two sides have
/// winding numbers near +1/2 and -1/2 (their magnitudes do not tell them
/// apart): inside is where the winding number, signed by the surface's
/// prevailing orientation, exceeds 1/10.
/// `unsure`, when given, receives the share of tetrahedra whose label the
/// winding number alone leaves open (settled by their neighbours).
/// `seal_box`, when given (a tile's box, EncodeOptions::seal_box): the
/// surface is a piece of a larger one cut off around the box. The caps that
/// ClosedSurface places outside the box close its cuts and are not
/// subtracted: the piece closed by them is the whole surface's solid inside
/// the box. (Subtracted, a cap across an oblique cut moved the winding
/// numbers of the tetrahedra near it towards 1/2: a 60,000-point torus in
/// 7 tiles had 59 open edges in its merged surface, and none with them
/// kept.) The caps of the surface's own holes, and of cuts no cap outside
/// the box closes, are subtracted as without a seal. Same `seal_box` for
/// every call on one cache.
std::vector<std::uint8_t> truth_labels(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                       const std::vector<Vec3>& surface_points, const std::vector<Triangle>& surface,
                                       const std::vector<Triangle>& input_faces_on_points,
                                       WindingCache* cache = nullptr, bool sheet = false, double* unsure = nullptr,
                                       const std::array<std::uint32_t, 6>* seal_box = nullptr);

/// Share of tetrahedra whose label the winding number leaves open
/// (truth_labels' `unsure`) above which the encoder also plans an open
/// surface read as a sheet, and keeps the reading that sends less side
/// information: the Stanford bunny, a solid with a few holes, leaves 0.4 %
/// open, an open tube 21 %, a height field 99 %.
constexpr double kSheetUnsure = 0.1;

/// Components (of faces joined by edges) and Euler characteristic of a
/// triangle list.
std::pair<std::size_t, long> surface_topology(const std::vector<Triangle>& faces);

/// Components (of faces joined by edges) and Euler characteristic of the
/// surface between inside and outside tetrahedra.
std::pair<std::size_t, long> interface_topology(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside);

/// What tuning chose and what it costs.
struct TuningReport {
  std::uint64_t mismatches_before_toggles = 0;
  /// The tetrahedra the chosen toggles invert (whichever form lists them).
  std::uint64_t corrections = 0;
  std::uint64_t side_bits_estimate = 0;
  /// The rule's labels for the chosen parameters (after the repair when
  /// they set it), before toggles, for reconstruct_from_labels(); empty
  /// when tuning had nothing to tune.
  std::vector<std::uint8_t> labels;
  /// The candidate flags (candidate_flags()) when the chosen parameters
  /// set candidate_contexts, for reconstruct_from_labels(); else empty.
  std::vector<std::uint8_t> candidates;
};

/// What the encoder knows about the input, on the level's points.
struct TuneInput {
  std::vector<std::uint8_t> truth;     ///< truth_labels(); empty: input without connectivity
  std::vector<std::uint32_t> border;   ///< border vertices of an open surface (sorted)
  const std::vector<Vec3>* surface_points = nullptr;    ///< grid units
  const std::vector<Triangle>* surface = nullptr;       ///< the input surface, for hole faces
  /// Fidelity::shape leaves mismatched tetrahedra thinner than this (grid
  /// units) to the rule; negative: 0.1% of the diagonal below.
  double shape_tolerance = -1;
  /// EncodeOptions::tolerance_diagonal: the length the drop list's and
  /// shape's tolerances are 1/1000 of; 0: the points' bounding-box diagonal.
  double diagonal = 0;
  /// A coarser level, which only approximates the input: instead of
  /// following `truth`, keep the rule's labels and correct only what makes
  /// the surface unsound (vertices left off it, non-manifold edges).
  bool approximate = false;
  /// Components and Euler characteristic the surface should keep (those of
  /// the finest level's input); components 0: unknown.
  std::size_t target_components = 0;
  long target_euler = 0;
  /// The truth may be unsound (a level of octree cells: the input's surface carried
  /// over to the decoded points, which can fold): after following it, mend
  /// its defects and steer towards the target topology before toggling.
  bool clean_target = false;
  /// Helper threads (EncodeOptions::threads): with one free, trials that do
  /// not depend on each other are evaluated two at a time (then decided in
  /// order, so the choice is the same).
  HelperBudget* helpers = nullptr;
  /// The seal of every trial's parameters (ReconParams::seal, spec 11.3):
  /// EncodeOptions::seal_box.
  bool seal = false;
  std::array<std::uint32_t, 6> seal_box{};
};

/// Side information for `in.truth`: alpha classes, peeling, the border
/// list, toggles for the labels the rule still gets wrong — all of them
/// (Fidelity::exact), all but flat tetrahedra thinner than 0.1% of the
/// bounding-box diagonal (Fidelity::shape, unless they change the topology;
/// Fidelity::topology, except the groups of them that change the Euler
/// characteristic: see tune()'s comments), or none (Fidelity::rule) — and,
/// for open surfaces, the faces that stray more than 0.1% of the diagonal
/// from the input (hole caps). Without truth: default parameters.
ReconParams tune(const std::vector<GridPoint>& points, const Tetrahedralization& dt, Kind kind, const TuneInput& in,
                 Fidelity fidelity, TuningReport* report = nullptr);

}  // namespace hmc::detail
