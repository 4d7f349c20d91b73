// SPDX-License-Identifier: AGPL-3.0-or-later
// Vector-quantizer training (encoder side, non-normative): a codebook of 3D
// displacement vectors by the LBG algorithm (splitting, then Lloyd
// iterations). Deterministic: the same training vectors in the same order
// give the same codebook on every IEEE-754 machine (no fused multiply-add,
// a fixed order of every sum).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hmc/codec.hpp"
#include "util/kdtree.hpp"

namespace hmc::detail {

using VqVector = std::array<double, 3>;

/// When Lloyd iterations stop: after `max_iterations`, or when the mean
/// squared error decreases by less than `tolerance` times its previous value.
struct LloydRule {
  int max_iterations = 50;
  double tolerance = 1e-4;
};

/// LBG codebook of min(k, distinct training vectors) entries for `data`
/// (k >= 1). Starts from the mean; each stage splits every codeword c whose
/// cell has per-axis standard deviations sigma into c - 0.2 sigma and
/// c + 0.2 sigma (when fewer splits are needed to reach the size, the cells
/// with the largest total squared error split, ties to the lower index),
/// then runs Lloyd iterations: each vector goes to its nearest codeword
/// (ties to the lower index), each codeword moves to its cell's mean, and an
/// empty cell takes the vector farthest from its codeword (ties to the
/// lower vector index). Returns the codewords (not rounded).
std::vector<VqVector> train_lbg(const std::vector<VqVector>& data, std::size_t k, const LloydRule& rule = {});

/// Mean squared distance of `data` to its nearest codeword.
double quantization_mse(const std::vector<VqVector>& data, const std::vector<VqVector>& codebook);

/// Codewords rounded to the nearest integer (halves away from zero) and
/// clamped to the VQTB range ±(2^21 − 1).
VectorQuantizer round_codebook(const std::vector<VqVector>& codebook);

/// A k-d tree over codewords, for nearest-codeword search.
KdTree<double> codebook_tree(const std::vector<VqVector>& codebook);

}  // namespace hmc::detail
