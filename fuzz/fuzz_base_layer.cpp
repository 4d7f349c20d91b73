// SPDX-License-Identifier: AGPL-3.0-or-later
// Fuzz target: the base-layer coders (decode_base: plain octree, coder 0,
// and the ranked octree, coder 5) on arbitrary bits.
//
// Input: u8 q (mapped to 1..21), u24 point count minus one (low 18 bits:
// at most 2^18 points, the decode target's limit), then the BASE payload
// (coder byte first). Checks: only bad_layer / bad_huffman_table are
// raised; a decoded set has exactly n distinct points on the 2^q grid in
// canonical order; encoding it again and decoding gives the same set.
#include <vector>

#include "fuzz_check.hpp"
#include "pointset/octree.hpp"
#include "util/error.hpp"

namespace {

using hmc::GridPoint;
using hmc::Status;

bool less(const GridPoint& a, const GridPoint& b) {
  return a[0] != b[0] ? a[0] < b[0] : a[1] != b[1] ? a[1] < b[1] : a[2] < b[2];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hmc_fuzz::Params params(data, size);
  const int q = 1 + params.u8() % 21;
  const std::uint64_t n = 1 + (params.u24() & 0x3ffff);

  std::vector<GridPoint> points;
  try {
    points = hmc::detail::decode_base(params.rest(), params.rest_size(), q, n);
  } catch (const hmc::detail::StreamError& e) {
    const Status s = e.error().status;
    FUZZ_CHECK(s == Status::bad_layer || s == Status::bad_huffman_table, "decode_base raised %s: %s",
               hmc::status_name(s), e.what());
    return 0;
  }
  FUZZ_CHECK(points.size() == n, "%zu points decoded, %llu asked for", points.size(),
             static_cast<unsigned long long>(n));
  const std::uint32_t cells = std::uint32_t{1} << q;
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < 3; ++a)
      FUZZ_CHECK(points[i][a] < cells, "point %zu coordinate %u outside the 2^%d grid", i, points[i][a], q);
    FUZZ_CHECK(i == 0 || less(points[i - 1], points[i]), "points %zu and %zu are not in strict canonical order",
               i - 1, i);
  }

  // The encoder's stream for the set decodes to the same set. (It may be
  // longer or shorter than the input: tables written differently cost
  // different bits, so only the sets are compared.)
  const std::vector<std::uint8_t> again = hmc::detail::encode_base(points, q);
  std::vector<GridPoint> back;
  try {
    back = hmc::detail::decode_base(again.data(), again.size(), q, n);
  } catch (const hmc::detail::StreamError& e) {
    FUZZ_CHECK(false, "a re-encoded set does not decode: %s", e.what());
  }
  FUZZ_CHECK(back == points, "re-encoding changed the point set");
  // The canonical encoding is a fixed point (checked on small sets only, to
  // keep the largest inputs well under the 5 s timeout).
  if (n <= 4096) FUZZ_CHECK(hmc::detail::encode_base(back, q) == again, "encoding is not deterministic");
  return 0;
}
