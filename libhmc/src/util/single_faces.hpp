// SPDX-License-Identifier: AGPL-3.0-or-later
// The boundary of a set of tetrahedra as the faces that only one of them
// has: shared by the encoder's input boundary (reconstruct/winding) and the
// hierarchy's boundary classification.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace hmc::detail {

/// Faces, each given with its own orientation, whose vertex set occurs
/// exactly once in `faces`, in ascending order of the sorted vertex triple
/// (a set used twice or more, as between two tetrahedra, is dropped).
inline std::vector<std::array<std::uint32_t, 3>> single_faces(const std::vector<std::array<std::uint32_t, 3>>& faces) {
  // The sorted triple (a, b, c) as the pair (a·2^32 + b, c), with the face's
  // index: integer comparisons instead of array ones.
  struct Key {
    std::uint64_t hi;
    std::uint32_t lo, index;
  };
  std::vector<Key> keys(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    auto s = faces[i];
    if (s[0] > s[1]) std::swap(s[0], s[1]);
    if (s[1] > s[2]) std::swap(s[1], s[2]);
    if (s[0] > s[1]) std::swap(s[0], s[1]);
    keys[i] = {std::uint64_t{s[0]} << 32 | s[1], s[2], static_cast<std::uint32_t>(i)};
  }
  std::sort(keys.begin(), keys.end(),
            [](const Key& x, const Key& y) { return x.hi != y.hi ? x.hi < y.hi : x.lo < y.lo; });
  std::vector<std::array<std::uint32_t, 3>> out;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i + 1;
    while (j < keys.size() && keys[j].hi == keys[i].hi && keys[j].lo == keys[i].lo) ++j;
    if (j == i + 1) out.push_back(faces[keys[i].index]);
    i = j;
  }
  return out;
}

}  // namespace hmc::detail
