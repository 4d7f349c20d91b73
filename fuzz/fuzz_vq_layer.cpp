// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: the anchored vector-quantizer refinement coder (REFN coder 1,
// decode_vq_layer) on arbitrary bits, against a coarser level and a
// codebook built from the input.
//
// Input: u8 q (mapped to 1..21), u8 coarse count c (1..64), c points of
// 3 x u24 (masked to the grid), u8 codebook size K (1..32), K entries of
// 3 x u24 taken as signed 24-bit values clamped to +-(2^21 - 1), u16 added
// count n (1..4096), then the layer's bit stream (without its coder byte).
// Checks: only bad_layer / bad_huffman_table are raised; a decoded layer has
// exactly n distinct points on the grid, none in the coarser level, in
// canonical order; coding them again with residual step 1 (the exact form
// of coder 1) keeps every point and decodes to the same points.
#include <algorithm>
#include <vector>

#include "fuzz_check.hpp"
#include "pointset/anchored_vq.hpp"
#include "util/error.hpp"

namespace {

std::int32_t signed24(std::uint32_t v) {
  const std::int32_t s = static_cast<std::int32_t>(v & 0xFFFFFFu) - ((v & 0x800000u) ? (1 << 24) : 0);
  return std::clamp(s, -((1 << 21) - 1), (1 << 21) - 1);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hmc_fuzz::Params params(data, size);
  int q = 0;
  const std::vector<hmc::GridPoint> coarse = hmc_fuzz::read_coarse_level(params, q);
  hmc::VectorQuantizer vq;
  const int k = 1 + params.u8() % 32;
  for (int i = 0; i < k; ++i) vq.codebook.push_back({signed24(params.u24()), signed24(params.u24()), signed24(params.u24())});
  const std::uint64_t n = 1 + params.u16() % 4096;

  std::vector<hmc::GridPoint> added;
  try {
    added = hmc::detail::decode_vq_layer(params.rest(), params.rest_size(), q, coarse, vq, n);
  } catch (const hmc::detail::StreamError& e) {
    const hmc::Status s = e.error().status;
    FUZZ_CHECK(s == hmc::Status::bad_layer || s == hmc::Status::bad_huffman_table, "decode_vq_layer raised %s: %s",
               hmc::status_name(s), e.what());
    return 0;
  }
  hmc_fuzz::check_added_layer(added, coarse, n, q);
  hmc::detail::VqLayerOptions exact;
  exact.step = 1;
  const auto again = hmc::detail::encode_vq_layer(coarse, added, vq, q, exact);
  FUZZ_CHECK(again.decoded == added, "the exact coder changed the points it codes");
  std::vector<hmc::GridPoint> back;
  try {
    back = hmc::detail::decode_vq_layer(again.bytes.data(), again.bytes.size(), q, coarse, vq, n);
  } catch (const hmc::detail::StreamError& e) {
    FUZZ_CHECK(false, "a re-encoded layer does not decode: %s", e.what());
  }
  FUZZ_CHECK(back == added, "re-encoding changed the added points");
  return 0;
}
