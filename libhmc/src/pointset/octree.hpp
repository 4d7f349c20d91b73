// SPDX-License-Identifier: AGPL-3.0-or-later
// Octree occupancy coding of a set of grid points (spec "Base layer:
// octree coder"). The set is coded, not a sequence: the stream is the same
// for any order of the input, and the decoder outputs the points in
// canonical order.
#pragma once

#include <cstdint>
#include <vector>

#include "codec/coders.hpp"
#include "entropy/huffman.hpp"
#include "hmc/codec.hpp"
#include "util/helpers.hpp"
#include "util/morton.hpp"

namespace hmc::detail {

/// Code distinct points (any order) on a 2^q grid. Returns the bit-stream
/// bytes (padded to a byte boundary).
std::vector<std::uint8_t> encode_octree(const std::vector<GridPoint>& points, int q);

/// Decode exactly `n` points; raises bad_layer / bad_huffman_table on a
/// malformed payload. The result is in canonical (x, y, z) ascending order.
std::vector<GridPoint> decode_octree(const std::uint8_t* data, std::size_t size, int q, std::uint64_t n,
                                     TableForm form = TableForm::deltas);

/// The whole BASE payload (spec section 8): a coder byte, then coder 0
/// (encode_octree) or coder 5, the ranked octree, whichever is smaller by 1%
/// at least. Coder 5 ranks a node's children by the plane (or, per depth, the
/// quadric) through the nearest nodes of its depth, those already decoded
/// replaced by their occupied children, with a gap weight per depth (16:
/// the far ranking, for volume interiors), each table paired where that is
/// smaller. The encoder ranks a depth only when that saves at least 2% of the
/// depth's bits, since every ranked node costs the decoder a
/// nearest-neighbour search. `coder`: BaseCoder::octree for coder 0 alone
/// (decoding speed). `helpers`: where one is free, it ranks half of each
/// large depth's nodes (the same stream).
std::vector<std::uint8_t> encode_base(const std::vector<GridPoint>& points, int q,
                                      BaseCoder coder = BaseCoder::ranked, HelperBudget* helpers = nullptr);

/// Decode a BASE payload (coder byte first) of exactly `n` points, in
/// canonical order; bad_layer for an unknown coder.
/// `form`: the stream's code-length table syntax (HEAD flag bit 0).
/// `helpers`: where one is free, the ranked coder's nearest-node searches
/// run on it, ahead of the decoding (same result).
std::vector<GridPoint> decode_base(const std::uint8_t* data, std::size_t size, int q, std::uint64_t n,
                                   TableForm form = TableForm::deltas, HelperBudget* helpers = nullptr);

/// The point of a Morton key of depth q (the inverse of morton_key,
/// util/morton.hpp).
GridPoint morton_point(std::uint64_t key, int q);

/// Sort points into canonical order (ascending x, then y, then z).
void sort_canonical(std::vector<GridPoint>& points);

}  // namespace hmc::detail
