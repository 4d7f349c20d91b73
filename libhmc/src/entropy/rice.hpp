// SPDX-License-Identifier: AGPL-3.0-or-later
// Rice codes of sorted index lists (spec 10.2): the gaps between entries,
// each as a unary quotient and k low bits.
#pragma once

#include <cstdint>
#include <vector>

namespace hmc::detail {

/// The Rice parameter (0..31) that codes `gaps` in the fewest bits, and
/// those bits (quotients, stop bits and low bits; no count, no parameter).
struct RiceChoice {
  int k = 0;
  std::uint64_t bits = 0;
};

inline RiceChoice best_rice(const std::vector<std::uint64_t>& gaps) {
  // bits(k) = S(k) + n (1 + k), S(k) = the sum of g >> k, is convex in k:
  // S(k) - S(k + 1) sums ceil((g >> k) / 2), which cannot grow with k, so
  // bits(k + 1) - bits(k) = n - (S(k) - S(k + 1)) cannot fall. The first k
  // from which bits stop falling is the first with the fewest bits.
  const std::uint64_t n = gaps.size();
  std::uint64_t sum = 0;  // S(k)
  for (auto g : gaps) sum += g;
  int k = 0;
  for (; k < 31; ++k) {
    std::uint64_t next = 0;  // S(k + 1)
    for (auto g : gaps) next += g >> (k + 1);
    if (sum - next <= n) break;
    sum = next;
  }
  return {k, sum + n * static_cast<std::uint64_t>(1 + k)};
}

/// The gaps of a sorted list of distinct indices: the first entry, then
/// each entry minus the previous minus 1.
inline std::vector<std::uint64_t> index_gaps(const std::vector<std::uint32_t>& list) {
  std::vector<std::uint64_t> gaps;
  gaps.reserve(list.size());
  std::uint64_t next = 0;
  for (std::uint32_t v : list) gaps.push_back(v - next), next = std::uint64_t{v} + 1;
  return gaps;
}

/// Bits of one list of spec 10.2: ue(count), then the parameter and the
/// codes when the list is not empty.
/// `count` (spec 0.24's neighbour contexts): the value the count field
/// carries, if not the list's length.
inline std::uint64_t rice_list_bits(const std::vector<std::uint32_t>& list, std::uint64_t count = ~std::uint64_t{0}) {
  std::uint64_t x = (count == ~std::uint64_t{0} ? list.size() : count) + 1, z = 0;
  while (x >> (z + 1)) ++z;
  if (list.empty()) return 2 * z + 1;
  return 2 * z + 1 + 5 + best_rice(index_gaps(list)).bits;
}

}  // namespace hmc::detail
