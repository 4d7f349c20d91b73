// SPDX-License-Identifier: AGPL-3.0-or-later
// LSD radix sort of 64-bit keys whose set bits all lie below `key_bits`.
// Point sets are sorted by integer keys (Morton or canonical) millions at
// a time; this is several times faster than a comparison sort there.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace hmc::detail {

inline void radix_sort(std::vector<std::uint64_t>& keys, int key_bits) {
  if (keys.size() < 256) {
    std::sort(keys.begin(), keys.end());
    return;
  }
  constexpr int kDigit = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigit;
  std::vector<std::uint64_t> tmp(keys.size());
  std::vector<std::size_t> count(kBuckets);
  for (int shift = 0; shift < key_bits; shift += kDigit) {
    std::fill(count.begin(), count.end(), 0);
    for (std::uint64_t k : keys) ++count[(k >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (auto& c : count) {
      const std::size_t n = c;
      c = sum;
      sum += n;
    }
    for (std::uint64_t k : keys) tmp[count[(k >> shift) & (kBuckets - 1)]++] = k;
    keys.swap(tmp);
  }
}

}  // namespace hmc::detail
