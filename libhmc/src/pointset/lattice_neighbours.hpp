// SPDX-License-Identifier: AGPL-3.0-or-later
// Exact k nearest occupied cells of one octree depth, the searches of the
// ranked base coder (spec 8.2): the nodes of a depth are integer cells, so
// the cells near a node can be looked up in a small dense grid instead of
// searched for in a k-d tree.
//
// The nodes are visited in Morton order, block by block (a block is the
// 8 x 8 x 8 cells below one node of depth d - 3). For the block of the node
// asked about, the grid holds the indices of every node within 4 cells of
// the block; the cells around the node are then read in order of distance.
// Ties go to the smaller index, as in KdTree.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "hmc/codec.hpp"
#include "pointset/octree.hpp"
#include "util/morton.hpp"

namespace hmc::detail {

class LatticeNeighbours {
 public:
  /// `cells`: the nodes of depth d (coordinates 0 ... 2^d - 1), with
  /// `keys` their Morton keys at depth d, ascending; a node's index is its
  /// position. Both must outlive this object.
  LatticeNeighbours(const LatticeNeighbours&) = delete;
  LatticeNeighbours& operator=(const LatticeNeighbours&) = delete;
  LatticeNeighbours(const std::vector<GridPoint>& cells, const std::vector<std::uint64_t>& keys, int d)
      : cells_(cells), keys_(keys), d_(d), bits_(std::min(d, kBlockBits)) {
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::uint64_t b = keys[i] >> (3 * bits_);
      if (blocks_.empty() || blocks_.back().key != b) blocks_.push_back({b, static_cast<std::uint32_t>(i)});
    }
    grid_.assign(kSide * kSide * kSide, 0);
  }

  /// Average nodes per occupied block: below a few, loading the blocks
  /// costs more than a k-d tree's searches.
  double density() const {
    return blocks_.empty() ? 0.0 : static_cast<double>(keys_.size()) / static_cast<double>(blocks_.size());
  }

  /// The min(k, n) nearest nodes to node i, by (squared distance, index)
  /// ascending, written to `out` (at most kMaxK); returns their number, or
  /// -1 when they are not all within kMargin cells of node i (then another
  /// search must answer).
  int nearest(std::size_t i, int k, std::uint32_t* out) {
    const std::uint64_t block = keys_[i] >> (3 * bits_);
    if (block != loaded_) load(block);
    const GridPoint& c = cells_[i];
    const std::int32_t base[3] = {static_cast<std::int32_t>(c[0]) - origin_[0], static_cast<std::int32_t>(c[1]) - origin_[1],
                                  static_cast<std::int32_t>(c[2]) - origin_[2]};
    std::array<std::uint64_t, kMaxCandidates> found;  // r2 << 32 | index
    int n = 0;
    std::int32_t last = -1;  // r2 of the k-th node found
    for (const Offset& o : offsets()) {
      if (n >= k && o.r2 > last) break;
      const std::uint32_t at = grid_[static_cast<std::size_t>(((base[0] + o.dx) * kSide + base[1] + o.dy) * kSide +
                                                               base[2] + o.dz)];
      if (at == 0) continue;
      if (n == kMaxCandidates) return -1;
      found[static_cast<std::size_t>(n++)] = (std::uint64_t{static_cast<std::uint32_t>(o.r2)} << 32) | (at - 1);
      if (n == k) last = o.r2;
    }
    if (n < k) return -1;  // fewer than k within reach: the search must look farther
    std::sort(found.begin(), found.begin() + n);
    for (int j = 0; j < k; ++j) out[j] = static_cast<std::uint32_t>(found[static_cast<std::size_t>(j)]);
    return k;
  }

  static constexpr int kMaxK = 15;

 private:
  static constexpr int kBlockBits = 3;                        // blocks of 8^3 cells
  static constexpr std::int32_t kMargin = 4;                  // cells around a block the grid covers
  static constexpr std::int32_t kSide = (1 << kBlockBits) + 2 * kMargin;
  static constexpr int kMaxCandidates = 64;
  struct Offset {
    std::int32_t dx, dy, dz, r2;
  };
  struct Block {
    std::uint64_t key;
    std::uint32_t first;  // index of its first node
  };

  // Every offset within kMargin cells (Euclidean), by squared length.
  static const std::vector<Offset>& offsets() {
    static const std::vector<Offset> list = [] {
      std::vector<Offset> v;
      for (std::int32_t x = -kMargin; x <= kMargin; ++x)
        for (std::int32_t y = -kMargin; y <= kMargin; ++y)
          for (std::int32_t z = -kMargin; z <= kMargin; ++z)
            if (x * x + y * y + z * z <= kMargin * kMargin) v.push_back({x, y, z, x * x + y * y + z * z});
      std::stable_sort(v.begin(), v.end(), [](const Offset& a, const Offset& b) { return a.r2 < b.r2; });
      return v;
    }();
    return list;
  }

  // Fill the grid with the nodes of the block `key` and of the blocks
  // around it that lie within kMargin cells of it.
  void load(std::uint64_t key) {
    for (std::uint32_t at : written_) grid_[at] = 0;
    written_.clear();
    loaded_ = key;
    const GridPoint b = morton_point(key, d_ - bits_);
    const std::int32_t side = 1 << bits_;
    for (int a = 0; a < 3; ++a) origin_[a] = static_cast<std::int32_t>(b[a]) * side - kMargin;
    const std::int64_t blocks_per_axis = std::int64_t{1} << (d_ - bits_);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const std::int64_t p[3] = {std::int64_t{b[0]} + dx, std::int64_t{b[1]} + dy, std::int64_t{b[2]} + dz};
          if (p[0] < 0 || p[1] < 0 || p[2] < 0 || p[0] >= blocks_per_axis || p[1] >= blocks_per_axis ||
              p[2] >= blocks_per_axis)
            continue;
          const std::uint64_t nk = morton_key({static_cast<std::uint32_t>(p[0]), static_cast<std::uint32_t>(p[1]),
                                               static_cast<std::uint32_t>(p[2])},
                                              d_ - bits_);
          const auto it = std::lower_bound(blocks_.begin(), blocks_.end(), nk,
                                           [](const Block& x, std::uint64_t v) { return x.key < v; });
          if (it == blocks_.end() || it->key != nk) continue;
          const std::uint32_t end = it + 1 == blocks_.end() ? static_cast<std::uint32_t>(keys_.size()) : (it + 1)->first;
          for (std::uint32_t j = it->first; j < end; ++j) {
            std::int32_t l[3];
            bool inside = true;
            for (int a = 0; a < 3; ++a) {
              l[a] = static_cast<std::int32_t>(cells_[j][static_cast<std::size_t>(a)]) - origin_[a];
              inside = inside && l[a] >= 0 && l[a] < kSide;
            }
            if (!inside) continue;
            const auto at = static_cast<std::uint32_t>((l[0] * kSide + l[1]) * kSide + l[2]);
            grid_[at] = j + 1;
            written_.push_back(at);
          }
        }
  }

  const std::vector<GridPoint>& cells_;
  const std::vector<std::uint64_t>& keys_;
  int d_, bits_;
  std::vector<Block> blocks_;
  std::vector<std::uint32_t> grid_, written_;
  std::uint64_t loaded_ = ~std::uint64_t{0};
  std::int32_t origin_[3] = {0, 0, 0};
};

}  // namespace hmc::detail
