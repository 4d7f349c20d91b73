// SPDX-License-Identifier: AGPL-3.0-or-later
// Anchored vector-quantizer coding of a refinement layer (spec "Refinement
// layer", coder 1): each added point is sent as a coarse point (its anchor,
// gap-coded in canonical order), a codebook index and, optionally, a scalar
// residual with a step s; the decoded point is the anchor plus the
// codeword plus s times the residual, clamped to the grid. Lossy unless
// s = 1. The decoder uses integer arithmetic only; the encoder trains the
// codebook and chooses anchors and indices.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "entropy/huffman.hpp"
#include "hmc/codec.hpp"

namespace hmc::detail {

/// Encoder choices for one layer.
struct VqLayerOptions {
  std::uint32_t step = 0;  ///< residual step s; 0: no residual (the codeword alone)
  int anchors = 4;         ///< candidate anchors per point: its nearest coarse points
};

/// One coded layer, with what the decoder will make of it.
struct VqLayer {
  std::vector<std::uint8_t> bytes;  ///< the coder's bit stream (without the coder byte)
  /// decoded[j] is what added[j] becomes; kept[j] = 0 when the point was
  /// dropped because no free grid point was within reach.
  std::vector<GridPoint> decoded;
  std::vector<std::uint8_t> kept;
  std::uint64_t displaced = 0;      ///< points moved off their best code to avoid a collision
  std::uint64_t dropped = 0;
  double max_error = 0;             ///< largest |added - decoded| over kept points (grid units)
  double sum_error2 = 0;            ///< sum of squared errors over kept points
};

/// Codes `added` (distinct grid points, any order) against `coarse` (the
/// decoded coarser level, distinct, any order) with codebook `vq` (1 to
/// 65536 entries). The stream depends only on the sets. An added point may
/// equal a coarse point (a lossy coarser layer put one of its points there):
/// it cannot decode to itself, so it takes the nearest free placement like
/// any point whose best code is taken (`displaced`), or is dropped. The
/// decoded points are always distinct and new, as the decoder requires.
VqLayer encode_vq_layer(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                        const VectorQuantizer& vq, int q, const VqLayerOptions& options);

/// Decodes exactly `n_added` points and returns them in canonical order.
/// Raises bad_layer (bit stream overrun, padding, bytes left, residual step
/// out of range, anchor beyond the coarse level, a point equal to a coarse
/// point or to another added point) or bad_huffman_table. `coarse` must be
/// canonical and non-empty, `vq` non-empty (invalid_argument otherwise).
std::vector<GridPoint> decode_vq_layer(const std::uint8_t* data, std::size_t size, int q,
                                       const std::vector<GridPoint>& coarse, const VectorQuantizer& vq,
                                       std::uint64_t n_added, TableForm form = TableForm::deltas);

/// One refinement layer of the training set: the coarser level's points
/// (original, before any lossy coding) and the points the layer adds.
struct VqTrainingLayer {
  const std::vector<GridPoint>* coarse = nullptr;
  const std::vector<GridPoint>* added = nullptr;
};

/// The codebook for `layers`: 2^bits entries at most (bits 0..16), trained
/// by LBG (quant/vector_quantizer.hpp) on the displacement of every added
/// point from its nearest coarse point (ties to the smaller canonical index),
/// then refined by Lloyd iterations in which each point picks, among its
/// `anchors` nearest coarse points and all codewords, the anchor and
/// codeword that predict it best, as encode_vq_layer does. Deterministic.
VectorQuantizer train_layer_codebook(const std::vector<VqTrainingLayer>& layers, int bits, int anchors);

}  // namespace hmc::detail
