// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Internal to the hierarchy module: the boundary faces of a level, and the
// free / fixed / removed labelling shared by the boundary and inner phases,
// which alone enforces the independent-set and minimum-size invariants of
// hierarchy.hpp.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "encoder/hierarchy/hierarchy.hpp"

namespace hmc::detail::hierarchy {

__extension__ typedef unsigned __int128 UInt128;

/// Whether a simplex counts (no repeated vertex); throws
/// std::invalid_argument on an index >= n.
template <std::size_t N>
bool usable(const std::array<std::uint32_t, N>& s, std::size_t n) {
  for (std::size_t i = 0; i < N; ++i) {
    if (s[i] >= n) throw std::invalid_argument("hierarchy: vertex index out of range");
    for (std::size_t j = 0; j < i; ++j)
      if (s[i] == s[j]) return false;
  }
  return true;
}

inline std::size_t point_count(const LevelMesh& m) { return m.points ? m.points->size() : 0; }

/// The boundary faces of `m` (see BoundaryAnalysis), oriented outward: the
/// usable triangles for a surface, the faces of exactly one tetrahedron for a
/// volume. Volume faces come in ascending order of their sorted vertex
/// triple; `on_boundary_face`, if given, is filled with 1 for their vertices.
std::vector<std::array<std::uint32_t, 3>> boundary_faces(const LevelMesh& m, Kind kind,
                                                         std::vector<std::uint8_t>* on_boundary_face = nullptr);

enum : std::uint8_t { kFree = 0, kFixed = 1, kRemoved = 2 };

struct Labelling {
  std::vector<std::uint8_t> label;
  std::vector<std::uint32_t> component;   // component id per vertex
  std::vector<std::size_t> component_left;  // vertices a component still keeps
  std::size_t min_keep = 3;               // m of hierarchy.hpp
  std::size_t removed = 0;

  /// Removes v if it is free and its component may lose a vertex; fixes its
  /// neighbours. Returns whether v was removed.
  bool try_remove(const VertexGraph& g, std::uint32_t v) {
    if (label[v] != kFree || component_left[component[v]] <= min_keep) return false;
    label[v] = kRemoved;
    --component_left[component[v]];
    ++removed;
    for (const std::uint32_t* u = g.begin(v); u != g.end(v); ++u)
      if (label[*u] == kFree) label[*u] = kFixed;
    return true;
  }
};

/// All vertices free; components of the graph numbered in order of their
/// smallest vertex. Isolated vertices are fixed (never removed).
Labelling initial_labelling(const VertexGraph& g, std::size_t min_keep);

struct InnerOutcome {
  Labelling labelling;
  InnerOptimizer chosen = InnerOptimizer::forward;
  std::uint32_t central_layer = 0;
  UInt128 key_sum = 0;  // Σ key over retained inner vertices
  std::size_t retained = 0;
};

/// The inner phase of decimate() (see hierarchy.hpp), from `start`.
InnerOutcome run_inner(const VertexGraph& g, const InnerAnalysis& a, const Labelling& start, InnerOptimizer opt,
                       std::size_t budget);

}  // namespace hmc::detail::hierarchy
