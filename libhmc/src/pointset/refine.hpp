// SPDX-License-Identifier: AGPL-3.0-or-later
// Refinement-layer coding (spec "Refinement layer"): the points a level adds
// to the decoded coarser level. Only the octree of the added points is coded;
// each of its occupancies is sent in an order and with a code chosen from
// the coarse points around the node, which the decoder already has. Like the
// base layer, the set is coded, not a sequence: any input order gives the
// same bytes, and the decoder outputs the points in canonical order.
#pragma once

#include <cstdint>
#include <vector>

#include "entropy/huffman.hpp"
#include "hmc/codec.hpp"

namespace hmc::detail {

/// The exact REFN coders (spec 8A): the conditional octree (0), with plane
/// contexts (2), with plane contexts and gap ranking (3), with a gap weight
/// per depth (4), with quadric ranking (5), coder 5 with paired tables (6),
/// and coder 6 with far ranking (7).
enum class OctreeCoder : std::uint8_t {
  plain = 0, planes = 2, gap = 3, depth_gaps = 4, quadric = 5, paired = 6, far = 7
};

/// The header fields of a refinement layer: the number of coarse neighbours
/// that predict where added points lie (0 to 15; 0 disables the prediction),
/// the number of context classes (1 to 4), the plane contexts and the gap
/// weights, and the quadric's neighbours. The coder follows from them: 7 with
/// a far-ranked depth, 6 with paired tables, 5 with a quadric, else 4 when
/// the depths' weights differ, 3 when they are equal and above 0, else 2
/// with plane contexts, else 0.
struct RefinementParams {
  int neighbours = 4;
  int classes = 4;
  /// Coders 2 and 3 (spec 8A.3, 8A.4): tables also chosen by whether the
  /// plane fitted to the neighbours crosses the node.
  bool plane_contexts = false;
  /// Coder 3 (spec 8A.4), 0 to 15: how much a child's distance from the
  /// nearest neighbour moves it up the ranking (0: not at all, coders 0, 2);
  /// kFarRanking (16) for every depth: coder 7's far ranking.
  int gap = 0;
  /// Coder 4 (spec 8A.5): when not empty, q weights (0 to 15), one per
  /// depth, in place of `gap`. Coder 7 (spec 8A.8): a weight may also be
  /// kFarRanking (16), which ranks that depth's children farthest from the
  /// nearest neighbour first.
  std::vector<int> depth_gaps;
  /// Coder 5 (spec 8A.6) when above 0, to 15: the children are ranked by
  /// their distance from the quadric fitted to this many nearest coarse
  /// points (none below 6), with the gap weights of coders 3 and 4.
  int fit = 0;
  /// Coder 6 (spec 8A.7): coder 5's header and ranking with a flag per
  /// table, each table paired (spec 7.4) where that codes it in fewer bits.
  bool paired = false;
};

/// A refinement layer as the encoder writes it: the REFN coder number (0,
/// 2, 3, 4, 5, 6 or 7, an OctreeCoder) and its bits.
struct RefinementLayer {
  std::uint8_t coder = 0;
  std::vector<std::uint8_t> bytes;
};

/// Codes `added` (distinct grid points, none in `coarse`, any order) given
/// `coarse` (distinct grid points in canonical order, at least one) on a 2^q
/// grid. The encoder tries a few parameter choices and keeps the smallest
/// stream. Returns the bit-stream bytes (empty when `added` is empty).
/// Raises invalid_argument when the preconditions do not hold.
std::vector<std::uint8_t> encode_refinement(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                                            int q);

/// The same with the header fields fixed by the caller (tests, measurements);
/// they select the coder (see RefinementParams).
std::vector<std::uint8_t> encode_refinement(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                                            int q, const RefinementParams& params);

/// What the encoder writes: coder 0, 2, 3, 4, 5, 6 or 7, whichever is smallest;
/// with `fast`, the smallest without neighbours (no search while decoding).
RefinementLayer encode_refinement_layer(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                                        int q, bool fast = false);

/// Decodes exactly `n_added` points; returns them in canonical order. Raises
/// bad_layer or bad_huffman_table on malformed data, never reads out of
/// bounds; memory is bounded by coarse.size() + n_added and work by q times
/// that, whatever `n_added` claims. `coarse` must be canonical and non-empty
/// (invalid_argument otherwise). `coder`: which coder's bits these are.
std::vector<GridPoint> decode_refinement(const std::uint8_t* data, std::size_t size, int q,
                                         const std::vector<GridPoint>& coarse, std::uint64_t n_added,
                                         TableForm form = TableForm::deltas, OctreeCoder coder = OctreeCoder::plain);

}  // namespace hmc::detail
