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

/// The two header fields of a refinement layer: the number of coarse
/// neighbours that predict where added points lie (0 to 15; 0 disables the
/// prediction), and the number of context classes (1 to 4).
struct RefinementParams {
  int neighbours = 4;
  int classes = 4;
  /// Coder 2 (spec 8A.3): tables also chosen by whether the plane fitted to
  /// the neighbours crosses the node.
  bool plane_contexts = false;
};

/// A refinement layer as the encoder writes it: the REFN coder number (0,
/// the conditional octree, or 2, the same with plane contexts) and its bits.
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
/// `params.plane_contexts` selects the bits of coder 2.
std::vector<std::uint8_t> encode_refinement(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                                            int q, const RefinementParams& params);

/// What the encoder writes: coder 0 or coder 2, whichever is smaller.
RefinementLayer encode_refinement_layer(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                                        int q);

/// Decodes exactly `n_added` points; returns them in canonical order. Raises
/// bad_layer or bad_huffman_table on malformed data, never reads out of
/// bounds; memory is bounded by coarse.size() + n_added and work by q times
/// that, whatever `n_added` claims. `coarse` must be canonical and non-empty
/// (invalid_argument otherwise). `plane_contexts`: the bits of coder 2.
std::vector<GridPoint> decode_refinement(const std::uint8_t* data, std::size_t size, int q,
                                         const std::vector<GridPoint>& coarse, std::uint64_t n_added,
                                         TableForm form = TableForm::deltas, bool plane_contexts = false);

}  // namespace hmc::detail
