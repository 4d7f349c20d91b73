// SPDX-License-Identifier: AGPL-3.0-or-later
#include "delaunay/adjacency.hpp"

#include <algorithm>

namespace hmc::detail {

namespace {
struct FaceRecord {
  std::uint64_t key;  // (middle vertex << 32) | largest vertex
  std::uint32_t face; // 4 * tet + local face
};
}  // namespace

bool build_adjacency(const std::vector<std::array<std::uint32_t, 4>>& tets, std::size_t num_points,
                     std::vector<std::array<std::uint32_t, 4>>& neighbors, std::string* error) {
  auto fail_with = [&](std::string m) {
    if (error) *error = std::move(m);
    return false;
  };
  const std::size_t nt = tets.size();
  if (nt > (std::size_t{1} << 30)) return fail_with("too many tetrahedra");
  neighbors.assign(nt, {kNoTet, kNoTet, kNoTet, kNoTet});

  auto face_of = [&](std::size_t f) {
    const auto& t = tets[f >> 2];
    const int* lv = kFaceVertices[f & 3];
    std::array<std::uint32_t, 3> s{t[lv[0]], t[lv[1]], t[lv[2]]};
    if (s[0] > s[1]) std::swap(s[0], s[1]);
    if (s[1] > s[2]) std::swap(s[1], s[2]);
    if (s[0] > s[1]) std::swap(s[0], s[1]);
    return s;
  };

  // Counting sort of the faces by their smallest vertex, then a small sort
  // inside each bucket: a face's twin has the same smallest vertex.
  std::vector<std::uint32_t> start(num_points + 1, 0);
  for (const auto& t : tets)
    for (std::uint32_t v : t)
      if (v >= num_points) return fail_with("vertex index out of range");
  for (std::size_t f = 0; f < 4 * nt; ++f) ++start[face_of(f)[0] + 1];
  for (std::size_t i = 0; i < num_points; ++i) start[i + 1] += start[i];
  std::vector<FaceRecord> rec(4 * nt);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < 4 * nt; ++f) {
      const auto s = face_of(f);
      rec[fill[s[0]]++] = {(static_cast<std::uint64_t>(s[1]) << 32) | s[2], static_cast<std::uint32_t>(f)};
    }
  }
  for (std::size_t a = 0; a < num_points; ++a) {
    auto* lo = rec.data() + start[a];
    auto* hi = rec.data() + start[a + 1];
    if (hi - lo <= 48) {
      for (auto* i = lo + 1; i < hi; ++i)  // buckets hold about 27 faces on average
        for (auto* j = i; j > lo && j[-1].key > j->key; --j) std::swap(j[-1], j[0]);
    } else {
      std::sort(lo, hi, [](const FaceRecord& x, const FaceRecord& y) { return x.key < y.key; });
    }
    for (auto* r = lo; r < hi;) {
      auto* e = r + 1;
      while (e < hi && e->key == r->key) ++e;
      if (e - r > 2) return fail_with("face shared by more than two tetrahedra");
      if (e - r == 2) {
        neighbors[r[0].face >> 2][r[0].face & 3] = r[1].face >> 2;
        neighbors[r[1].face >> 2][r[1].face & 3] = r[0].face >> 2;
      }
      r = e;
    }
  }
  return true;
}

std::vector<HullFace> hull_faces(const std::vector<std::array<std::uint32_t, 4>>& tets,
                                 const std::vector<std::array<std::uint32_t, 4>>& neighbors) {
  std::vector<HullFace> out;
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (int k = 0; k < 4; ++k)
      if (neighbors[t][k] == kNoTet) {
        const int* lv = kFaceVertices[k];
        out.push_back({{tets[t][lv[0]], tets[t][lv[1]], tets[t][lv[2]]}, static_cast<std::uint32_t>(t), k});
      }
  return out;
}

}  // namespace hmc::detail
