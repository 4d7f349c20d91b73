// SPDX-License-Identifier: AGPL-3.0-or-later
//
// The level-of-detail hierarchy (thesis §3.1–3.4, brief steps 6–8): which
// vertices of one level are removed — and so travel in that level's
// refinement layer — to form the next coarser level.
//
// Encoder side and non-normative: a decoder never runs this code; it only
// receives the points that survive. Geometry is evaluated in binary64 (with
// integer arithmetic where exactness is cheap), every loop runs in a fixed
// order, and every tie is broken by the smaller vertex index, so the result
// is a deterministic function of the LevelMesh and the options.
//
// Overview of one call to decimate():
//
//   1. Vertex graph (vertex_graph): two vertices are adjacent iff they share
//      an edge of a triangle (surface kind) or of a tetrahedron (volume
//      kind). A surface ignores LevelMesh::tetrahedra, a volume ignores
//      LevelMesh::triangles. Simplices that repeat a vertex index are
//      skipped everywhere in this module; an index >= points->size() throws
//      std::invalid_argument (this is an internal, encoder-side interface).
//
//   2. Classification (classify, §3.2–3.3): boundary / inner.
//
//   3. Boundary decimation (§3.4.1): every boundary vertex gets a type and
//      an error (analyze_boundary); candidates whose error is below Dmax are
//      removed smallest error first (ties: smaller index), up to the budget.
//
//   4. Inner decimation (§3.4.2, volumes only): BFS layers from the
//      boundary, importance IP (eq. 3.1), forward / backward / greedy /
//      central-layer labellings, keep the best (analyze_inner, decimate).
//
// Invariants of the returned removal set, for every mode and optimiser:
//   * Independent set: no two removed vertices are adjacent in the vertex
//     graph. (Removing a vertex "fixes" its neighbours: they are never
//     removed at this level. A vertex is only removed while it is free, and a
//     free vertex never has a removed neighbour.)
//   * Minimum size: let m = 4 for a volume, 3 for a surface. A vertex is
//     removed only while its connected component (in the vertex graph) keeps
//     more than m vertices, so every component keeps at least min(size, m)
//     vertices, components of at most m vertices are never touched, and the
//     level keeps at least m vertices whenever it had them. Vertices of no
//     simplex (isolated points) are never removed.
//   * Budgets: at most round(target_ratio * B) boundary vertices and at most
//     round(target_ratio * I) inner vertices are removed, B and I being the
//     numbers of boundary and inner vertices of the level, round(x) =
//     floor(x + 0.5), target_ratio clamped to [0, 1]. Independence (and Dmax)
//     may stop the removal earlier; target_ratio = 1 asks for the maximal
//     removal these rules allow.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hmc/codec.hpp"

namespace hmc::detail {

/// One level's mesh: indices into `points` (grid points, integers below
/// 2^21).
struct LevelMesh {
  const std::vector<GridPoint>* points = nullptr;
  /// Surface kind: a closed or open triangle surface, consistently oriented
  /// (outward for a closed one). Orientation only matters for feature edges:
  /// two neighbouring triangles of opposite orientation meet at about 180°
  /// and so make a feature edge.
  std::vector<std::array<std::uint32_t, 3>> triangles;
  /// Volume kind: positively oriented tetrahedra (orient3d > 0). A negatively
  /// oriented one is accepted (its boundary faces are flipped to face
  /// outward); a flat one still counts for faces and edges.
  std::vector<std::array<std::uint32_t, 4>> tetrahedra;
};

/// Dmax policy of the boundary decimation (§3.4.1.1–3).
enum class BoundaryMode {
  /// Dmax0 is chosen at the first decimated level (see DecimationState) as
  /// the smallest value that lets that level reach its boundary budget —
  /// precisely: the removal runs on all candidates in ascending error order
  /// until the budget is met or the candidates run out, and Dmax0 is the
  /// next binary64 value above the error of the last vertex removed (0 if
  /// none was). Every later level uses the same Dmax0.
  constant,
  /// Dmax0 chosen as for `constant`; level k uses Dmax_k = Dmax0 * (1 + k -
  /// k0), k0 being the level at which Dmax0 was chosen (normally 0; a level
  /// k < k0 uses Dmax0).
  linear,
  /// Per level and per local region. Each boundary candidate v is ranked by
  /// its normalised error (e(v) * M) / h(v), where h(v) is v's local edge
  /// length — its longest incident edge in the level's vertex graph, i.e.
  /// its local alpha of §2.3.2 — and M is the lower median (element
  /// (k − 1) / 2 of the k sorted values) of h over the level's boundary
  /// candidates; a candidate with h(v) = 0 (coincident points) is dropped.
  /// Equivalently v's threshold is Dmax_k *
  /// h(v) / M: coarse regions tolerate larger errors. Dmax_k (in normalised
  /// units) is chosen at every level as Dmax0 is chosen for `constant`
  /// (DecimationState::dmax0 is neither used nor set).
  adaptive,
};

/// Inner-vertex labelling strategy (§3.4.2.2). See decimate() for the
/// precise rules.
enum class InnerOptimizer { forward, backward, greedy, best };

// --------------------------------------------------------------------------
// Vertex graph

/// Adjacency of a level's vertices in compressed form: the neighbours of v
/// are nbr[offset[v]] .. nbr[offset[v + 1] - 1], in ascending index order.
struct VertexGraph {
  std::vector<std::uint32_t> offset;  ///< size n + 1
  std::vector<std::uint32_t> nbr;

  std::size_t size() const noexcept { return offset.empty() ? 0 : offset.size() - 1; }
  std::uint32_t degree(std::uint32_t v) const noexcept { return offset[v + 1] - offset[v]; }
  const std::uint32_t* begin(std::uint32_t v) const noexcept { return nbr.data() + offset[v]; }
  const std::uint32_t* end(std::uint32_t v) const noexcept { return nbr.data() + offset[v + 1]; }
};

/// The vertex graph of `m` for `kind` (surface: triangle edges; volume:
/// tetrahedron edges; any other kind: no edges), over all points->size()
/// vertices.
VertexGraph vertex_graph(const LevelMesh& m, Kind kind);

// --------------------------------------------------------------------------
// Classification (§3.2, §3.3)

/// A vertex is inner by the solid-angle method iff the solid angles of its
/// tetrahedra sum to at least 4π − kSolidAngleTolerance (steradians). Each
/// solid angle is 2·atan2(|6V|, |a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|)
/// (Van Oosterom–Strackee) with the triple product 6V computed exactly;
/// the rounding error of a sum is below 1e-12 sr, far under the tolerance.
inline constexpr double kSolidAngleTolerance = 1e-9;

/// Per vertex, 1 = boundary, 0 = inner.
///
/// Surface kind: every vertex is a boundary vertex (both arrays all 1).
/// Volume kind:
///   * boundary (normative for decimation): the vertex lies on a face that
///     belongs to exactly one tetrahedron (exact, combinatorial; the vtk
///     method of §3.3);
///   * boundary_by_angle: the solid angles of its tetrahedra sum to less
///     than 4π − kSolidAngleTolerance (§3.2).
/// A vertex of no tetrahedron (or, for any other kind, every vertex) is a
/// boundary vertex by both methods. The two methods agree on every vertex of
/// a valid (embedded, non-overlapping) tetrahedral mesh except where the
/// free solid angle at a boundary vertex is below the tolerance (a hairline
/// crack); `disagreements` counts the vertices where they differ.
struct Classification {
  std::vector<std::uint8_t> boundary;           ///< by faces, normative for decimation
  std::vector<std::uint8_t> boundary_by_angle;  ///< by solid-angle sum
  std::size_t disagreements = 0;
  std::vector<double> solid_angle;  ///< volume kind: the sum per vertex (sr); empty otherwise
  std::size_t boundary_count = 0;   ///< number of 1s in `boundary`
  /// Volume kind: the boundary faces (those of one tetrahedron only, as
  /// hierarchy::boundary_faces gives them), kept for analyze_boundary so
  /// that the faces are sorted once per level; empty otherwise.
  std::vector<std::array<std::uint32_t, 3>> faces;
};

Classification classify(const LevelMesh& m, Kind kind);

// --------------------------------------------------------------------------
// Boundary geometry (§3.4.1)

/// Dihedral threshold of feature edges, degrees (vtkDecimatePro's default
/// feature angle is 15°; we use 45° as the brief suggests, so only real
/// creases count, not the facets of a coarse sphere).
inline constexpr double kDefaultFeatureAngleDeg = 45.0;

enum class BoundaryVertexType : std::uint8_t {
  none = 0,    ///< inner vertex, or a vertex of no boundary face: not a boundary candidate
  simple = 1,  ///< no feature edge: error = distance to the plane of its boundary neighbours
  line = 2,    ///< on a border or feature line: error = distance to the chord
  corner = 3,  ///< never removed
};

/// Per-vertex boundary geometry of one level.
///
/// Boundary faces: the triangles (surface kind), or the faces owned by one
/// tetrahedron, oriented outward (volume kind). A boundary edge is an edge
/// of a boundary face; it is a *feature edge* iff it is
///   * a border edge (one boundary face) or non-manifold (three or more), or
///   * shared by two faces whose normals make an angle greater than the
///     feature angle (cos(angle) < cos(feature angle)), or
///   * an edge of a boundary face of zero area (no normal: conservative).
/// The type of a boundary vertex v with f incident feature edges:
///   * corner if its boundary faces do not form one edge-connected fan
///     (a pinch point, non-manifold), or if f = 1 or f >= 3;
///   * f = 2, line neighbours a and b (the other ends of its two feature
///     edges): corner if the line turns at v by more than the feature angle
///     (the angle between v − a and b − v; e.g. the corner of a flat square
///     sheet), else `line` with error = Euclidean distance from v to the
///     segment [a, b];
///   * f = 0: `simple`, error = |n · (v − c)| / |n|, where c is the
///     centroid of its boundary neighbours (the other vertices of its
///     boundary faces, each counted once) and n = Σ (q − p) × (r − p) over
///     its boundary faces (p, q, r) — the area-weighted normal. The
///     numerator is evaluated exactly in integers as |n · (k·v − Σ u)| / k,
///     so a vertex coplanar with its neighbours has error exactly 0. If
///     n = 0 the error is +infinity (never removed).
struct BoundaryAnalysis {
  std::vector<BoundaryVertexType> type;
  std::vector<double> error;         ///< +infinity unless type is simple or line
  std::vector<double> local_length;  ///< longest incident edge in the vertex graph (0 if isolated)
  std::size_t boundary_faces = 0;
  std::size_t feature_edges = 0;
};

BoundaryAnalysis analyze_boundary(const LevelMesh& m, Kind kind, const Classification& c, const VertexGraph& g,
                                  double feature_angle_deg = kDefaultFeatureAngleDeg);

// --------------------------------------------------------------------------
// Inner layers and importance (§3.4.2.1)

inline constexpr std::uint32_t kNoLayer = 0xFFFFFFFFu;

/// Layers by breadth-first search in the vertex graph: L0 = the boundary
/// vertices (Classification::boundary), L(k+1) = the unlabelled vertices
/// adjacent to Lk. total_layers = 1 + the deepest layer index (the L0 ..
/// Ln columns of thesis tables 4.7/4.9/4.11). A vertex no boundary vertex
/// reaches (only in invalid inputs, e.g. a closed 3-pseudomanifold) has
/// layer kNoLayer: it is never removed and is counted in L0's statistics.
///
/// Importance, eq. 3.1:
///   IP(n) = ((MaxDegree − Degree(n)) / MaxDegree) · ((TotalLayers − Layer(n)) / TotalLayers)
/// with Degree = number of neighbours in the vertex graph and MaxDegree its
/// maximum over all vertices of the level. The order of removal uses the
/// exact integer key(n) = (MaxDegree − Degree(n)) · (TotalLayers − Layer(n)),
/// which is IP times a positive constant: smallest key first, ties by the
/// smaller index — i.e. deep, highly connected vertices go first.
struct InnerAnalysis {
  std::vector<std::uint32_t> layer;
  std::vector<std::uint32_t> degree;
  std::uint32_t max_degree = 0;
  std::uint32_t total_layers = 0;
  std::vector<std::uint64_t> key;  ///< meaningful for layer >= 1 (inner vertices)

  /// IP(n) as a double: key / (MaxDegree · TotalLayers).
  double ip(std::uint32_t v) const noexcept;
};

/// eq. 3.1 for given values (0 when max_degree or total_layers is 0).
double importance(std::uint32_t max_degree, std::uint32_t degree, std::uint32_t total_layers,
                  std::uint32_t layer) noexcept;

InnerAnalysis analyze_inner(const VertexGraph& g, const Classification& c);

// --------------------------------------------------------------------------
// Decimation

struct DecimationOptions {
  Kind kind = Kind::surface;
  /// Fraction of the level's boundary vertices, and separately of its inner
  /// vertices, to remove at most (see "Budgets" above).
  double target_ratio = 0.3;
  BoundaryMode boundary = BoundaryMode::constant;
  InnerOptimizer optimizer = InnerOptimizer::best;
  /// Index of the level being decimated (0 = finest), for the linear mode.
  int level = 0;
  double feature_angle_deg = kDefaultFeatureAngleDeg;
};

/// State carried from level to level. Start with a default-constructed one
/// and pass it to the decimation of level 0, 1, 2, ... in turn.
struct DecimationState {
  /// Dmax0 of the constant and linear modes; negative = not chosen yet (it
  /// is then chosen by the next call, at that call's level).
  double dmax0 = -1;
  int first_level = 0;              ///< the level at which dmax0 was chosen
  std::vector<double> dmax_history; ///< the Dmax used by each call, in order
};

struct LayerStats {
  std::size_t vertices = 0, removed = 0;
};

struct DecimationResult {
  /// Per vertex of the level: 1 = removed (goes to this level's refinement
  /// layer).
  std::vector<std::uint8_t> removed;
  Classification classification;
  /// L0 (boundary) ... Ln for volumes; a single L0 = all vertices for
  /// surfaces. Σ vertices = points->size(), Σ removed = number of 1s in
  /// `removed`.
  std::vector<LayerStats> layers;
  /// The Dmax used at this level (normalised units in adaptive mode).
  double dmax = 0;
  /// Mean IP (eq. 3.1) of the retained inner vertices (0 if none).
  double mean_ip_retained = 0;
  /// The optimiser whose labelling was kept: the requested one, or for
  /// `best` the winner. `best` itself here means that a central-layer
  /// variant won, the one starting at layer `central_layer`.
  InnerOptimizer chosen = InnerOptimizer::forward;
  std::uint32_t central_layer = 0;  ///< 0 unless a central-layer variant won
  /// Boundary vertices eligible at this level: type simple or line with
  /// error below the vertex's threshold.
  std::size_t boundary_candidates = 0, boundary_removed = 0, inner_removed = 0;
  std::size_t boundary_budget = 0, inner_budget = 0;
};

/// Decimates one level.
///
/// Boundary phase (both kinds). Candidates: vertices of type simple or line
/// (analyze_boundary) whose error (normalised in adaptive mode) is below
/// Dmax; they are visited in ascending (error, index) order and each one
/// that is still free is removed, fixing its neighbours (inner ones too),
/// until the boundary budget is met. Dmax follows BoundaryMode and `state`.
///
/// Inner phase (volume kind). Starts from the labelling left by the
/// boundary phase; only inner vertices (layer >= 1) are considered, in the
/// order of InnerAnalysis's key within a group of vertices; a vertex that is
/// still free is removed and its neighbours fixed, until the inner budget
/// is met. The groups, processed one after another:
///   * forward:  L1, L2, ..., Ln (inward);
///   * backward: Ln, ..., L2, L1 (outward);
///   * greedy:   one group holding all inner layers;
///   * central layer c (2 <= c <= n − 1): Lc, then inward L(c+1) ... Ln, then
///     outward L(c−1) ... L1 (c = 1 is forward and c = n backward, so they
///     are not repeated);
///   * best: runs all of the above and keeps the labelling whose retained
///     inner vertices have the highest mean IP (compared exactly, on the
///     integer keys); ties prefer forward, backward, greedy, then the
///     smaller c.
/// Because a removal fixes its neighbours in every layer at once, "first fix
/// the vertices adjacent to already removed ones" holds in every layer
/// before its own removals start.
DecimationResult decimate(const LevelMesh& m, const DecimationOptions& o, DecimationState& state);

}  // namespace hmc::detail
