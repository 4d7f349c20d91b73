// SPDX-License-Identifier: AGPL-3.0-or-later
// The plane ranking of a node's children (spec "Refinement layer", 8A.1,
// "Ranking of the children", shared by the ranked base-layer coder, 8.2):
// children nearest to the plane fitted to the node's neighbours come first,
// and occupancies are sent as ranked occupancies, ordered by number of set
// bits, so likely symbols get small indices. Exact 64-bit integer arithmetic.
#pragma once

#include <array>
#include <cstdint>

#include "hmc/codec.hpp"

namespace hmc::detail {

/// Non-zero occupancies ordered by number of set bits, then value (the list
/// E of the spec): occupancy[s] is E[s], index[E[s]] = s.
struct OccupancyOrder {
  std::array<std::uint8_t, 256> index{};
  std::array<std::uint8_t, 255> occupancy{};
  OccupancyOrder();
};
const OccupancyOrder& occupancy_order();

/// The symbol of `occupancy` (spec 8A.1, "Symbols") when the children are
/// ranked by `order` (order[r] = the child of rank r): the index in E of the
/// ranked occupancy.
inline std::uint8_t ranked_symbol(const std::array<int, 8>& order, unsigned occupancy) {
  unsigned ranked = 0;
  for (std::size_t r = 0; r < 8; ++r) ranked |= ((occupancy >> order[r]) & 1u) << r;
  return occupancy_order().index[ranked];
}

/// The occupancy that `symbol` stands for when the children are ranked by
/// `order`: the inverse of ranked_symbol.
inline unsigned occupancy_of(const std::array<int, 8>& order, std::uint32_t symbol) {
  const unsigned ranked = occupancy_order().occupancy[symbol];
  unsigned occupancy = 0;
  for (std::size_t r = 0; r < 8; ++r) occupancy |= ((ranked >> r) & 1u) << order[r];
  return occupancy;
}

int popcount8(unsigned v);

/// Point in doubled grid coordinates (below 2^22).
using Doubled = std::array<std::int32_t, 3>;

/// The most points a node's children are ranked by: the cap of the base
/// coder's causal points (spec 8.2), above the refinement coders' 15.
inline constexpr int kMaxRankPoints = 32;

/// The ranking weight that stands for far ranking (spec 8A.1, REFN coder 7):
/// children farthest from the nearest neighbour first, the plane (or
/// quadric) and centroid distances only breaking ties.
inline constexpr int kFarRanking = 16;
/// The width of the weight fields that can hold it (BASE coder 5, REFN
/// coder 7; the coders before them have 4-bit weights, 0 to 15).
inline constexpr int kFarWeightBits = 5;

/// The keys that rank a node's children (spec 8A.1 steps 2–4, and 8A.1's
/// distances to the nearest neighbour when `with_gaps`), computed once so
/// that the encoder can rank the children for several gap weights.
class ChildKeys {
 public:
  /// `gap_from`: the distances to the nearest neighbour skip the first
  /// gap_from neighbours (the base coder's node itself, spec 8.2). `fit`
  /// (spec 8A.1): when 6 or more, the plane distances give way to distances
  /// from the quadric fitted to the first `fit` neighbours (where that fit
  /// is well posed; `fit` is at most kMaxRankPoints, and a larger one fits
  /// nothing); `neighbours` then holds max(k, fit) points, of which
  /// the plane and the gaps use the first k.
  /// `plane`, when given, also receives the keys of the same call with fit
  /// 0 (the plane's), from the work the two share.
  ChildKeys(const GridPoint& node, int d, int q, const Doubled* neighbours, int k, bool with_gaps, int gap_from = 0,
            int fit = 0, ChildKeys* plane = nullptr);
  /// No keys yet: a place for the `plane` keys of another call.
  ChildKeys() = default;
  /// How many children lie on the smaller side of the fitted plane (0 to 4).
  int split() const { return split_; }
  /// The ranking of rank_children (below) for gap weight `gap` (0 to 15;
  /// above 0 only when constructed `with_gaps`), or, for gap = kFarRanking,
  /// the far ranking of spec 8A.1 (without `with_gaps`, as if no neighbour
  /// were given).
  void order(unsigned first_mask, int gap, std::array<int, 8>& order) const;
  /// ranked_symbol() of `occupancy` (not 0) under that ranking, without
  /// sorting: the encoders' trials of several weights.
  std::uint8_t symbol(unsigned first_mask, int gap, unsigned occupancy) const;
  /// symbol(first_mask, gaps[j], occupancy) into out[j] for j < n: the same
  /// symbols, with one pass over the children per weight (the gapped keys
  /// of consecutive weights differ by a small multiple of one step).
  void symbols(unsigned first_mask, const int* gaps, std::size_t n, unsigned occupancy, std::uint8_t* out) const;

 private:
  __extension__ typedef unsigned __int128 UInt128;
  /// The keys from t_c, e_c and g_c (the constructor's last step).
  void finish(const std::array<std::int64_t, 8>& t, const std::array<std::int64_t, 8>& e,
              const std::array<std::int64_t, 8>& g, bool gapped, std::int64_t weight);
  /// Each child's sort key for weight `gap`: (not in first_mask, then the
  /// weight's key), distinct across the children.
  void keys(unsigned first_mask, int gap, std::array<UInt128, 8>& out) const;
  std::array<std::uint8_t, 8> tie_{};  // each child's place by (t, e, child number)
  bool gapped_ = false;                // a gap weight changes the order (k^2 |n|^2 > 0)
  std::array<UInt128, 8> base_{}, step_{};  // the sort keys (constructor)
  std::array<std::uint64_t, 8> far_{};      // the far ranking's keys (constructor)
  int split_ = 0;
};

/// order[r] = the child of rank r of the node `node` (integer coordinates at
/// depth d < q on a 2^q grid): children whose bit is set in `first_mask`
/// first, then by distance of the child's centre to the plane fitted to the
/// k `neighbours`, then by distance to their centroid, then by child number.
/// `split`, when given, receives how many children lie on the smaller side
/// of that plane (0 to 4; children on the plane count on neither side).
/// `gap` (0 to 15, spec 8A.1): with gap G > 0 the plane distance t gives way
/// to the key 32·t² − G·(squared distance of the child's centre to the
/// nearest neighbour), both in units of the plane's scale, so that children
/// far from every neighbour come earlier; gap 0 is the plain ranking.
void rank_children(const GridPoint& node, int d, int q, const Doubled* neighbours, int k, unsigned first_mask,
                   std::array<int, 8>& order, int* split = nullptr, int gap = 0, int gap_from = 0);

}  // namespace hmc::detail
