// SPDX-License-Identifier: AGPL-3.0-or-later
// LSD radix sort of 64-bit keys whose set bits all lie below `key_bits`.
// Point sets are sorted by integer keys (Morton or canonical) millions at
// a time; this is several times faster than a comparison sort there.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace hmc::detail {

/// `scratch` is working memory, resized to the keys' size; passing a vector
/// that already has the capacity saves an allocation.
inline void radix_sort(std::vector<std::uint64_t>& keys, int key_bits, std::vector<std::uint64_t>& scratch) {
  if (keys.size() < 256) {
    std::sort(keys.begin(), keys.end());
    return;
  }
  // As few passes as digits of at most 12 bits allow (4,096 counters stay
  // in cache), the bits shared out evenly among them.
  const int passes = std::max(1, (key_bits + 11) / 12);
  const int digit = (key_bits + passes - 1) / passes;
  const std::size_t buckets = std::size_t{1} << digit;
  std::vector<std::uint64_t>& tmp = scratch;
  tmp.resize(keys.size());
  std::vector<std::size_t> count(buckets);
  for (int shift = 0; shift < key_bits; shift += digit) {
    std::fill(count.begin(), count.end(), 0);
    for (std::uint64_t k : keys) ++count[(k >> shift) & (buckets - 1)];
    if (count[(keys[0] >> shift) & (buckets - 1)] == keys.size()) continue;  // one digit: already in order
    std::size_t sum = 0;
    for (auto& c : count) {
      const std::size_t n = c;
      c = sum;
      sum += n;
    }
    for (std::uint64_t k : keys) tmp[count[(k >> shift) & (buckets - 1)]++] = k;
    keys.swap(tmp);
  }
}

inline void radix_sort(std::vector<std::uint64_t>& keys, int key_bits) {
  std::vector<std::uint64_t> scratch;
  radix_sort(keys, key_bits, scratch);
}

}  // namespace hmc::detail
