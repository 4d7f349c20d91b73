// SPDX-License-Identifier: AGPL-3.0-or-later
// The boundary of a set of tetrahedra as the faces that only one of them
// has: shared by the encoder's input boundary (encoder/winding) and the
// hierarchy's boundary classification.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace hmc::detail {

/// Faces, each given with its own orientation, whose vertex set occurs
/// exactly once among the faces face_at(0) ... face_at(count - 1), in
/// ascending order of the sorted vertex triple (a set used twice or more, as
/// between two tetrahedra, is dropped). face_at is called about three times
/// per face, so that a caller can make the faces of its tetrahedra on the fly
/// instead of listing them all first (the hierarchy's boundary of a volume
/// level listed 4.8 MB of faces for skull_tetgen beside these keys).
template <class FaceAt>
std::vector<std::array<std::uint32_t, 3>> single_faces(std::size_t count, const FaceAt& face_at) {
  // Faces grouped by their smallest vertex a (a counting sort: linear), then
  // each group, a few dozen faces of one vertex, sorted by the pair (b, c):
  // the ascending order of the triples, without a comparison sort of every
  // face.
  struct Key {
    std::uint32_t b, c, index;
  };
  const auto sorted = [](std::array<std::uint32_t, 3> s) {
    if (s[0] > s[1]) std::swap(s[0], s[1]);
    if (s[1] > s[2]) std::swap(s[1], s[2]);
    if (s[0] > s[1]) std::swap(s[0], s[1]);
    return s;
  };
  std::uint32_t top = 0;
  for (std::size_t i = 0; i < count; ++i) top = std::max(top, sorted(face_at(i))[0]);
  // start[a] .. start[a + 1]: the faces whose smallest vertex is a.
  std::vector<std::size_t> start(count == 0 ? 1 : std::size_t{top} + 2, 0);
  for (std::size_t i = 0; i < count; ++i) ++start[std::size_t{sorted(face_at(i))[0]} + 1];
  for (std::size_t v = 1; v < start.size(); ++v) start[v] += start[v - 1];
  std::vector<Key> keys(count);
  {
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < count; ++i) {
      const auto s = sorted(face_at(i));
      keys[next[s[0]]++] = {s[1], s[2], static_cast<std::uint32_t>(i)};
    }
  }
  const auto less = [](const Key& x, const Key& y) { return x.b != y.b ? x.b < y.b : x.c < y.c; };
  const auto same = [](const Key& x, const Key& y) { return x.b == y.b && x.c == y.c; };
  std::vector<std::array<std::uint32_t, 3>> out;
  for (std::size_t v = 0; v + 1 < start.size(); ++v) {
    const auto first = keys.begin() + static_cast<std::ptrdiff_t>(start[v]);
    const auto last = keys.begin() + static_cast<std::ptrdiff_t>(start[v + 1]);
    std::sort(first, last, less);
    for (auto i = first; i != last;) {
      auto j = i + 1;
      while (j != last && same(*j, *i)) ++j;
      if (j == i + 1) out.push_back(face_at(i->index));
      i = j;
    }
  }
  return out;
}

/// The same for a list of faces (fewer than 2^32 of them).
inline std::vector<std::array<std::uint32_t, 3>> single_faces(const std::vector<std::array<std::uint32_t, 3>>& faces) {
  return single_faces(faces.size(), [&faces](std::size_t i) { return faces[i]; });
}

}  // namespace hmc::detail
