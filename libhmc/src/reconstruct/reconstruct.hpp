// SPDX-License-Identifier: AGPL-3.0-or-later
// Normative reconstruction of connectivity from a level's points (spec
// "Reconstruction"): every Delaunay tetrahedron is labelled inside or
// outside by a rule driven by the level's side information; a surface is
// the oriented interface between the two labels, a volume the inside
// tetrahedra. All decisions use exact integer arithmetic.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

#include "delaunay/delaunay.hpp"
#include "hmc/codec.hpp"
#include "util/helpers.hpp"

namespace hmc::detail {

/// Contexts of the compact toggle list (spec 11.5): a tetrahedron's label
/// before toggles and how many of its faces lie on the interface (0-3+),
/// 8 contexts; with candidate contexts (RCON flag bit 5, spec 0.20) also
/// how many of its faces are candidates (0-4), 40; with vertex contexts
/// (flag bit 6, spec 0.21) also whether its four vertices are all on the
/// interface, 80.
constexpr int kToggleContexts = 80;
constexpr int kCandidateContexts = 40;
constexpr int kLabelContexts = 8;
/// With neighbour contexts (flag bit 7, spec 0.24, with vertex contexts):
/// each of the 80 also split by how many of the tetrahedron's face
/// neighbours of smaller index are toggled (0, 1, 2 or more), 240.
constexpr int kNeighbourContexts = 3 * kToggleContexts;

/// Side information that drives the rule (the RCON chunk's content).
struct ReconParams {
  /// Rank k of the local scale: s_v is the k-th smallest squared length of
  /// the Delaunay edges at v (the largest if v has fewer than k).
  std::uint32_t scale_rank = 6;
  /// Alpha classes as multipliers of s_v in units of 1/256: vertex v
  /// admits edges with 256·d² <= s_v · multipliers[class(v)].
  std::vector<std::uint32_t> multipliers{512};
  /// Class of each vertex (canonical order); empty means all class 0.
  std::vector<std::uint8_t> vertex_class;
  /// Apply the peeling step.
  bool peel = true;
  /// Apply the repair step (spec 11.4a): make every point a vertex of the
  /// surface and every edge manifold where local flips can, keeping the
  /// topology.
  bool repair = false;
  /// Thresholds of the candidate filters of thesis §2.3.2 (0 = off), in
  /// units of 1/256 (spec "Reconstruction", 11.2a): circle radius, min/max
  /// edge ratio, density, lone triangle (1 = on), neighbour circle radius
  /// ratio, neighbour min/max edge ratio.
  std::array<std::uint32_t, 6> filters{};
  /// RCON filter_mask bit 6 (spec 0.26): the flood (spec 11.3) crosses no
  /// face without a vertex in `seal_box` (x0, y0, z0, x1, y1, z1: a
  /// half-open box of lattice coordinates), as if it were a candidate. A
  /// tile's stream (spec/tiles.md) is an open piece of a surface; its
  /// convex hull and the flat tetrahedra along its cuts, all between
  /// margin points, would let the flood into the inside of the cut solid.
  bool seal = false;
  std::array<std::uint32_t, 6> seal_box{};
  /// Border vertices of an open surface (sorted, distinct). As read from
  /// or written to a stream with `border_delta`, the list is the change to
  /// the inherited border instead (see resolve_border()).
  std::vector<std::uint32_t> border;
  /// RCON flag bit 3 (spec 0.9): `border` lists the points whose membership
  /// differs from the coarser level's border (its points, all of which are
  /// in this level), i.e. the symmetric difference of the two sets.
  bool border_delta = false;
  /// Compact coding (RCON flag bit 2, spec 0.5): alpha classes in groups
  /// and toggles as ranks within their context. Without it (streams up to
  /// spec 0.4), toggles are tetrahedron indices.
  bool compact = true;
  /// RCON flag bit 5 (spec 0.20, with compact): toggle contexts also count
  /// the tetrahedron's candidate faces (kToggleContexts instead of
  /// kLabelContexts).
  bool candidate_contexts = false;
  /// RCON flag bit 6 (spec 0.21, with candidate_contexts): toggle contexts
  /// also tell whether all four vertices are on the interface.
  bool vertex_contexts = false;
  /// RCON flag bit 7 (spec 0.24, with vertex_contexts): the toggles travel
  /// in `neighbour_lists` instead of `toggle_ranks`.
  bool neighbour_contexts = false;
  /// With neighbour_contexts: per context j < kNeighbourContexts (spec
  /// 11.5), sorted distinct ranks among the tetrahedra of context j in
  /// ascending index: of the toggled ones, or, where neighbour_inverted[j],
  /// of the ones not toggled. Both kNeighbourContexts long (else empty).
  std::vector<std::vector<std::uint32_t>> neighbour_lists;
  std::vector<std::uint8_t> neighbour_inverted;
  /// Tetrahedra whose label is inverted after the rule (sorted, distinct);
  /// only when !compact.
  std::vector<std::uint32_t> toggles;
  /// When compact: per context j (toggle_context()), the ranks, sorted and
  /// distinct, of the toggled tetrahedra among the tetrahedra of context j
  /// in ascending index.
  std::array<std::vector<std::uint32_t>, kToggleContexts> toggle_ranks;
  /// Surface faces left out of the output, as 4·tetrahedron + local face
  /// (sorted, distinct): faces across the holes of an open surface.
  std::vector<std::uint32_t> drops;
};

struct Reconstruction {
  std::vector<std::uint8_t> inside;          ///< per tetrahedron of the DT: 1 inside
  std::vector<Triangle> triangles;           ///< surface kind: oriented outward, canonical order
  std::vector<Tetrahedron> tetrahedra;       ///< volume kind: inside tetrahedra, canonical
};

/// The local scale s_v of every vertex (squared grid units).
/// `helpers`, here and below: where one is free, it takes half of the
/// independent per-element work (the same result).
std::vector<std::uint64_t> local_scale(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                       std::uint32_t rank, HelperBudget* helpers = nullptr);

/// What the neighbour filters (spec 11.2a d-f) are computed from: the faces
/// that pass the edge test and filters (a)-(c), and each one's neighbours
/// of largest circumradius and of largest edge ratio. It does not depend on
/// the neighbour filters' thresholds, so an encoder trying several of them
/// on one level passes one FilterMemo to each of those calls (same points,
/// same tetrahedralization, one call at a time): a call whose edge-test
/// flags, (a)-(c) thresholds and (where those are set) scale match the
/// memo's reuses it, any other recomputes it. The flags come out the same.
struct FilterMemo {
  bool valid = false;
  std::vector<std::uint8_t> cand;                  // the edge test's flags
  std::array<std::uint32_t, 3> face_thresholds{};  // filters (a)-(c)
  std::vector<std::uint64_t> scale;                // when (a)-(c) are set
  std::vector<std::array<std::uint32_t, 3>> faces;
  std::vector<std::array<std::uint32_t, 2>> face_slots;
  std::vector<std::uint8_t> keep, has;
  std::vector<std::uint32_t> max_r, max_ratio;
};

/// The squared lengths of every tetrahedron's six edges, (0,1), (0,2),
/// (0,3), (1,2), (1,3), (2,3) by local vertex, which the edge test (spec
/// 11.2) of every set of parameters compares with the vertices' limits: an
/// encoder trying many parameters on one level computes them once and
/// passes them to each call. 24 bytes per tetrahedron, kept only where
/// every squared length fits in 32 bits (points spanning at most 37,837
/// grid units on each axis, so every q <= 15); otherwise `d2` stays empty
/// and the calls compute the lengths themselves. Read only: calls on
/// several threads may share them.
struct TetEdgeLengths {
  std::vector<std::array<std::uint32_t, 6>> d2;
  TetEdgeLengths(const std::vector<GridPoint>& points, const Tetrahedralization& dt, HelperBudget* helpers = nullptr);
};

/// The peeling's decision (spec 11.4) for every tetrahedron and pair of
/// its faces that may be the exposed two: it depends on the four faces'
/// circumradii only, not on the parameters, so an encoder trying many
/// parameters with peeling on one level passes one PeelMemo to each call,
/// which decides each tetrahedron's six cases the first time it is needed
/// (byte per tetrahedron: bit 6 set when known, bit i the case of pair i).
/// Calls on several threads may share one: every call stores the same
/// value.
struct PeelMemo {
  explicit PeelMemo(std::size_t tets) : cases(tets) {}
  std::vector<std::atomic<std::uint8_t>> cases;
};

/// Candidate flag of every face slot, indexed 4·tetrahedron + local face:
/// the edge test against the alpha limits (spec 11.2) and the filters
/// (11.2a). Both slots of a face carry the same flag. `memo`: FilterMemo;
/// `edges`: TetEdgeLengths of these points and tetrahedra (the same flags).
std::vector<std::uint8_t> candidate_flags(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                          const std::vector<std::uint64_t>& scale, const ReconParams& p,
                                          HelperBudget* helpers = nullptr, FilterMemo* memo = nullptr,
                                          const TetEdgeLengths* edges = nullptr);

/// The labels of the rule before toggles (flood from the hull through
/// non-candidate faces, then peeling); `cand`, when given, receives the
/// candidate flags (candidate_flags(), with `memo` and `edges`); `peel_memo`:
/// PeelMemo of these points and tetrahedra (the same labels).
std::vector<std::uint8_t> rule_labels(const std::vector<GridPoint>& points, const Tetrahedralization& dt,
                                      const std::vector<std::uint64_t>& scale, const ReconParams& p,
                                      std::vector<std::uint8_t>* cand = nullptr, HelperBudget* helpers = nullptr,
                                      FilterMemo* memo = nullptr, const TetEdgeLengths* edges = nullptr,
                                      PeelMemo* peel_memo = nullptr);

/// The normative repair step (spec 11.4a) on rule labels: greedy local
/// flips around unsound vertices (surface kind: points off the surface;
/// both kinds: edges with other than two faces), each kept only if it
/// lowers the defects of the flipped tetrahedron's vertices and keeps the
/// surface's local Euler characteristic.
void repair_labels(const Tetrahedralization& dt, Kind kind, std::vector<std::uint8_t>& inside);

/// The greedy search of the repair step alone (spec 11.4a, after the
/// bubbles), with want[v] = 1 for the points that must be on the interface
/// (the spec's W): what repair_labels() runs after remove_bubbles(). Tests
/// hold it to the spec's pseudo-code.
void repair_search(const Tetrahedralization& dt, std::vector<std::uint8_t>& inside,
                   const std::vector<std::uint8_t>& want);

/// The tetrahedra around each vertex of `dt` (n vertices): those of v are
/// incident[start[v] .. start[v + 1]), in ascending index.
struct VertexTets {
  std::vector<std::uint32_t> start, incident;
};
VertexTets vertex_tets(const Tetrahedralization& dt, std::size_t n);

/// Work buffers of local_defects(), reused from call to call.
struct DefectScratch {
  std::vector<std::uint32_t> ends, parent;
  std::vector<std::uint64_t> sorted;
};

/// Defects of vertex v under the labels `inside` (spec 11.4a): 1 if it is
/// off the interface though `want[v]`; else the edges (v, w) on other than
/// two interface faces plus the fans of interface faces around v beyond the
/// first. `start`/`incident`: the tetrahedra incident to each vertex
/// (incident[start[v] .. start[v + 1])). Reads only the labels of the
/// tetrahedra incident to v. `on`, when given, receives whether v is on the
/// interface.
int local_defects(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside,
                  const std::vector<std::uint32_t>& start, const std::vector<std::uint32_t>& incident,
                  const std::vector<std::uint8_t>& want, std::uint32_t v, DefectScratch& work, bool* on = nullptr);

/// The count of local_defects() from the interface faces around a vertex,
/// listed in work.ends as the pairs of their other two vertices; `wanted`:
/// whether the vertex should be on the interface.
int defects_of_faces(bool wanted, DefectScratch& work, bool* on = nullptr);

/// Number of toggle contexts of `p`: kToggleContexts with vertex contexts,
/// kCandidateContexts with candidate contexts alone, else kLabelContexts.
inline int toggle_context_count(const ReconParams& p) {
  return p.vertex_contexts ? kToggleContexts : p.candidate_contexts ? kCandidateContexts : kLabelContexts;
}

/// Context of every tetrahedron for the compact toggle list (spec 11.5),
/// from the labels before toggles: 4 · label + min(3, faces on the
/// interface), a hull face counting for an inside tetrahedron; plus 8 ·
/// (its candidate faces) when `cand` (candidate_flags()) is given; plus 40
/// when `vertices` and its four vertices are all on the interface.
std::vector<std::uint8_t> toggle_contexts(const Tetrahedralization& dt, const std::vector<std::uint8_t>& inside,
                                          const std::vector<std::uint8_t>* cand = nullptr, bool vertices = false);

/// The toggled tetrahedra `toggled` (ascending) as ranks within their
/// contexts under the labels before toggles (encoder side of the above).
std::array<std::vector<std::uint32_t>, kToggleContexts> toggle_ranks(const Tetrahedralization& dt,
                                                                     const std::vector<std::uint8_t>& inside,
                                                                     const std::vector<std::uint32_t>& toggled,
                                                                     const std::vector<std::uint8_t>* cand = nullptr,
                                                                     bool vertices = false);

/// The same from contexts already computed (toggle_contexts()), for the
/// three context sets at once: [0] the 8 label contexts (modulo 8), [1] the
/// 40 with candidates (modulo 40), [2] all 80, in one pass.
using ToggleRanks = std::array<std::vector<std::uint32_t>, kToggleContexts>;
std::array<ToggleRanks, 3> toggle_ranks(const std::vector<std::uint8_t>& ctx, const std::vector<std::uint32_t>& toggled);

/// The neighbour contexts' lists (spec 11.5, flag bit 7) of the toggled
/// tetrahedra `toggled` (ascending), from the 80 contexts `ctx`
/// (toggle_contexts() with candidates and vertices): for each context j,
/// `ranks[j]` the ranks of its toggled tetrahedra and `sizes[j]` its number
/// of tetrahedra. The encoder lists either those ranks or the others.
struct NeighbourRanks {
  std::vector<std::vector<std::uint32_t>> ranks;
  std::vector<std::uint32_t> sizes;
};
NeighbourRanks neighbour_ranks(const Tetrahedralization& dt, const std::vector<std::uint8_t>& ctx,
                               const std::vector<std::uint32_t>& toggled);

/// Number of toggles `p` carries, in either form (with neighbour contexts,
/// the listed entries: an inverted list names tetrahedra left as they are).
std::size_t toggle_count(const ReconParams& p);

/// Invert the labels `p` toggles (spec 11.5); bad_layer for an index or a
/// rank that names no tetrahedron. `cand`: the candidate flags, needed when
/// p.candidate_contexts (internal_error without them).
void apply_toggles(const Tetrahedralization& dt, const ReconParams& p, std::vector<std::uint8_t>& inside,
                   const std::vector<std::uint8_t>* cand = nullptr);

/// Surface or volume from final labels (toggles applied by the caller);
/// of `p` only the border and drop lists are used.
Reconstruction extract(const Tetrahedralization& dt, Kind kind, const std::vector<std::uint8_t>& inside,
                       const ReconParams& p);

/// The border the coarser level passes on (spec 10, flag bit 3): the
/// indices in `points` (canonical order) of `coarse[i]` for i in
/// `coarse_border`, where `coarse` is the coarser level's point set, a
/// subset of `points`, and `coarse_border` its resolved border list.
std::vector<std::uint32_t> inherited_border(const std::vector<GridPoint>& points, const std::vector<GridPoint>& coarse,
                                            const std::vector<std::uint32_t>& coarse_border);

/// Symmetric difference of two sorted lists of distinct indices: the coded
/// list from the border set and the inherited one, or the set back from the
/// coded list.
std::vector<std::uint32_t> border_change(const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b);

/// Turns a border read with `border_delta` into the set (clearing the flag).
void resolve_border(ReconParams& p, const std::vector<std::uint32_t>& inherited);

/// The whole normative rule (on a resolved border).
Reconstruction reconstruct(const std::vector<GridPoint>& points, const Tetrahedralization& dt, Kind kind,
                           const ReconParams& p, HelperBudget* helpers = nullptr);

/// The end of reconstruct(): toggles (11.5), drops and extraction (11.6),
/// on the labels of the rule after peeling and, when p.repair, the repair
/// (a caller that has them, as the encoder's tuning does, skips the rest);
/// `cand` as for apply_toggles().
Reconstruction reconstruct_from_labels(const Tetrahedralization& dt, Kind kind, const ReconParams& p,
                                       std::vector<std::uint8_t> inside, const std::vector<std::uint8_t>* cand = nullptr);

/// Exact squared distance of two grid points (below 3·2^42).
inline std::uint64_t dist2(const GridPoint& a, const GridPoint& b) {
  std::uint64_t s = 0;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t d = static_cast<std::int64_t>(a[i]) - static_cast<std::int64_t>(b[i]);
    s += static_cast<std::uint64_t>(d * d);
  }
  return s;
}

/// Indices into ReconParams::filters.
enum FilterId { kCircleRadius = 0, kEdgeRatio = 1, kDensity = 2, kLone = 3, kNeighbourRadius = 4, kNeighbourRatio = 5 };
constexpr int kFilterCount = 6;
/// filter_mask bit 6 (spec 0.26): a seal box follows the thresholds; its
/// upper bounds are at most 2^21, the largest lattice's size.
constexpr int kSealBit = 6;
constexpr std::uint32_t kSealBound = 1u << 21;

/// Whether grid point g lies in the half-open seal box b (spec 11.3): the
/// one membership test of the flood and of the encoder's tuning.
inline bool in_seal_box(const GridPoint& g, const std::array<std::uint32_t, 6>& b) {
  for (int ax = 0; ax < 3; ++ax)
    if (g[ax] < b[ax] || g[ax] >= b[3 + ax]) return false;
  return true;
}

}  // namespace hmc::detail
