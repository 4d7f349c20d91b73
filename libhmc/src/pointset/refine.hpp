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

#include "codec/coders.hpp"
#include "entropy/huffman.hpp"
#include "hmc/codec.hpp"

namespace hmc::detail {

/// The header fields of a refinement layer (spec 8A.1): the number of coarse
/// neighbours that predict where added points lie (0 to 15; 0 disables the
/// prediction), the number of context classes (1 to 4), and the ranking
/// fields of the full header. The coder follows from them: 0 (the short
/// header) when they are all at their defaults, else 7.
struct RefinementParams {
  int neighbours = 4;
  int classes = 4;
  /// Tables also chosen by whether the plane fitted to the neighbours
  /// crosses the node (the plane context).
  bool plane_contexts = false;
  /// 0 to 15: how much a child's distance from the nearest neighbour moves
  /// it up the ranking (0: not at all); kFarRanking (16): the far ranking.
  int gap = 0;
  /// When not empty, q weights (0 to 15 or kFarRanking), one per depth, in
  /// place of `gap`.
  std::vector<int> depth_gaps;
  /// When above 0, to 15: the children are ranked by their distance from the
  /// quadric fitted to this many nearest coarse points (none below 6).
  int fit = 0;
  /// Each table paired (spec 7.4) where that codes it in fewer bits.
  bool paired = false;
};

/// A refinement layer as the encoder writes it: the REFN coder number (0 or
/// 7, a RefineCoder) and its bits.
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

/// What the encoder writes: coder 0 or 7, whichever is smallest;
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
                                         TableForm form = TableForm::deltas,
                                         RefineCoder coder = RefineCoder::conditional_octree);

}  // namespace hmc::detail
