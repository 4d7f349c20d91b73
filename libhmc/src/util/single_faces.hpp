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
  // Faces grouped by their smallest vertex a (a counting sort: linear), then
  // each group, a few dozen faces of one vertex, sorted by the pair (b, c)
  // as the number b·2^32 + c: the ascending order of the triples, without
  // a comparison sort of every face.
  struct Key {
    std::uint64_t bc;
    std::uint32_t index;
  };
  const auto smallest = [](const std::array<std::uint32_t, 3>& f) { return std::min(f[0], std::min(f[1], f[2])); };
  std::uint32_t top = 0;
  for (const auto& f : faces) top = std::max(top, smallest(f));
  // start[a] .. start[a + 1]: the faces whose smallest vertex is a.
  std::vector<std::size_t> start(faces.empty() ? 1 : std::size_t{top} + 2, 0);
  for (const auto& f : faces) ++start[std::size_t{smallest(f)} + 1];
  for (std::size_t v = 1; v < start.size(); ++v) start[v] += start[v - 1];
  std::vector<Key> keys(faces.size());
  {
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < faces.size(); ++i) {
      auto s = faces[i];
      if (s[0] > s[1]) std::swap(s[0], s[1]);
      if (s[1] > s[2]) std::swap(s[1], s[2]);
      if (s[0] > s[1]) std::swap(s[0], s[1]);
      keys[next[s[0]]++] = {std::uint64_t{s[1]} << 32 | s[2], static_cast<std::uint32_t>(i)};
    }
  }
  std::vector<std::array<std::uint32_t, 3>> out;
  for (std::size_t v = 0; v + 1 < start.size(); ++v) {
    const auto first = keys.begin() + static_cast<std::ptrdiff_t>(start[v]);
    const auto last = keys.begin() + static_cast<std::ptrdiff_t>(start[v + 1]);
    std::sort(first, last, [](const Key& x, const Key& y) { return x.bc < y.bc; });
    for (auto i = first; i != last;) {
      auto j = i + 1;
      while (j != last && j->bc == i->bc) ++j;
      if (j == i + 1) out.push_back(faces[i->index]);
      i = j;
    }
  }
  return out;
}

}  // namespace hmc::detail
