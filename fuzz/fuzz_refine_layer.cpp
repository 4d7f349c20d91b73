// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: the refinement-layer coder (decode_refinement) on arbitrary
// bits, against a coarser level built from the input.
//
// Input: u8 q (mapped to 1..21), u8 coarse count c (1..64), c points of
// 3 x u24 (masked to the grid), u16 added count n (1..4096), u8 coder (its
// value mod 2: 0 coder 0, the short header; 1 coder 7, the full header with
// plane contexts, the quadric, gap weights, far ranking and paired tables),
// then the REFN bit
// stream (without its coder byte). Checks: only bad_layer /
// bad_huffman_table are raised; a decoded layer has exactly n distinct new
// points on the grid, none in the coarser level, in canonical order; coding
// them again decodes to the same points.
#include <algorithm>
#include <vector>

#include "fuzz_check.hpp"
#include "pointset/refine.hpp"
#include "util/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hmc_fuzz::Params params(data, size);
  int q = 0;
  const std::vector<hmc::GridPoint> coarse = hmc_fuzz::read_coarse_level(params, q);
  const std::uint64_t n = 1 + params.u16() % 4096;
  // The two headers of the conditional octree (spec 8A.1): coder 0 and 7.
  const hmc::detail::RefineCoder coder = params.u8() % 2 ? hmc::detail::RefineCoder::ranked_octree
                                                         : hmc::detail::RefineCoder::conditional_octree;

  std::vector<hmc::GridPoint> added;
  try {
    added = hmc::detail::decode_refinement(params.rest(), params.rest_size(), q, coarse, n, hmc::detail::TableForm::deltas,
                                           coder);
  } catch (const hmc::detail::StreamError& e) {
    const hmc::Status s = e.error().status;
    FUZZ_CHECK(s == hmc::Status::bad_layer || s == hmc::Status::bad_huffman_table, "decode_refinement raised %s: %s",
               hmc::status_name(s), e.what());
    return 0;
  }
  hmc_fuzz::check_added_layer(added, coarse, n, q);
  const auto again = hmc::detail::encode_refinement_layer(coarse, added, q);
  std::vector<hmc::GridPoint> back;
  try {
    back = hmc::detail::decode_refinement(again.bytes.data(), again.bytes.size(), q, coarse, n,
                                          hmc::detail::TableForm::deltas,
                                          static_cast<hmc::detail::RefineCoder>(again.coder));
  } catch (const hmc::detail::StreamError& e) {
    FUZZ_CHECK(false, "a re-encoded layer does not decode: %s", e.what());
  }
  FUZZ_CHECK(back == added, "re-encoding changed the added points");
  return 0;
}
