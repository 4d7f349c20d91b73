// SPDX-License-Identifier: AGPL-3.0-or-later
// Exact k nearest occupied cells of one octree depth, the searches of the
// ranked base coder (spec 8.2): the nodes of a depth are integer cells, so
// the cells near a node can be looked up in a small dense grid instead of
// searched for in a k-d tree.
//
// Cells are grouped in buckets of 2^shift cells per axis (shift 0: one cell
// per bucket), chosen per depth so that the buckets near a node hold a few
// nodes. The nodes are visited in Morton order, block by block (a block is
// 8 x 8 x 8 buckets); for the block of the node asked about, a grid holds,
// for every bucket within 4 buckets of the block, the range of its nodes
// (those of a bucket are consecutive in Morton order). With single-cell
// buckets the cells around the node are read in order of distance; with
// larger ones, ring after ring of buckets until no bucket farther out can
// hold a nearer node. Ties go to the smaller index, as in KdTree.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <vector>

#include "hmc/codec.hpp"
#include "pointset/octree.hpp"
#include "util/morton.hpp"

namespace hmc::detail {

class LatticeNeighbours {
 public:
  static constexpr int kMaxK = 15;

  /// Average nodes per occupied block of 8^3 buckets of 2^shift cells, for
  /// nodes with Morton keys `keys` (ascending) at depth d.
  static double density(const std::vector<std::uint64_t>& keys, int d, int shift) {
    const int s = 3 * (shift + std::min(d - shift, kBlockBits));
    std::size_t blocks = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) blocks += i == 0 || (keys[i] >> s) != (keys[i - 1] >> s);
    return blocks == 0 ? 0.0 : static_cast<double>(keys.size()) / static_cast<double>(blocks);
  }

  /// `cells`: the nodes of depth d (coordinates 0 ... 2^d - 1), with
  /// `keys` their Morton keys at depth d, ascending; a node's index is its
  /// position. Both must outlive this object. 0 <= shift <= d.
  LatticeNeighbours(const LatticeNeighbours&) = delete;
  LatticeNeighbours& operator=(const LatticeNeighbours&) = delete;
  LatticeNeighbours(const std::vector<GridPoint>& cells, const std::vector<std::uint64_t>& keys, int d, int shift = 0)
      : cells_(cells), keys_(keys), shift_(shift), depth_(d - shift), bits_(std::min(d - shift, kBlockBits)) {
    const int s = 3 * (shift_ + bits_);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::uint64_t b = keys[i] >> s;
      if (blocks_.empty() || blocks_.back().key != b) blocks_.push_back({b, static_cast<std::uint32_t>(i)});
    }
    grid_.assign(kSide * kSide * kSide, Range{0, 0});
  }

  /// The min(k, n) nearest nodes to node i, by (squared distance, index)
  /// ascending, written to `out` (k <= kMaxK); returns their number, or -1
  /// when they are not all within reach of the grid (then another search
  /// must answer).
  int nearest(std::size_t i, int k, std::uint32_t* out) {
    const std::uint64_t block = keys_[i] >> (3 * (shift_ + bits_));
    if (block != loaded_) load(block);
    const GridPoint& c = cells_[i];
    std::int32_t base[3];  // the node's bucket in the grid
    for (int a = 0; a < 3; ++a) base[a] = static_cast<std::int32_t>(c[static_cast<std::size_t>(a)] >> shift_) - origin_[a];
    return shift_ == 0 ? nearest_cells(base, k, out) : nearest_buckets(c, base, k, out);
  }

 private:
  static constexpr int kBlockBits = 3;                        // blocks of 8^3 buckets
  static constexpr std::int32_t kMargin = 4;                  // buckets around a block the grid covers
  static constexpr std::int32_t kSide = (1 << kBlockBits) + 2 * kMargin;
  static constexpr int kMaxCandidates = 64;
  static constexpr std::uint32_t kMaxScan = 1024;  // distances computed per search, at most
  static_assert(kSide <= 16, "a column's occupancy is 16 bits");
  struct Offset {
    std::int32_t dx, dy, dz, r2;
  };
  struct Block {
    std::uint64_t key;
    std::uint32_t first;  // index of its first node
  };
  struct Range {
    std::uint32_t begin, end;  // the bucket's nodes
  };

  const Range& at(const std::int32_t (&base)[3], const Offset& o) const {
    return grid_[static_cast<std::size_t>(((base[0] + o.dx) * kSide + base[1] + o.dy) * kSide + base[2] + o.dz)];
  }

  // Single-cell buckets: the cells within kMargin, nearest first.
  int nearest_cells(const std::int32_t (&base)[3], int k, std::uint32_t* out) const {
    std::array<std::uint64_t, kMaxCandidates> found;  // r2 << 32 | index
    int n = 0;
    std::int32_t last = -1;  // r2 of the k-th node found
    for (const Offset& o : sphere()) {
      if (n >= k && o.r2 > last) break;
      const Range& r = at(base, o);
      if (r.begin == r.end) continue;
      if (n == kMaxCandidates) return -1;
      found[static_cast<std::size_t>(n++)] = (std::uint64_t{static_cast<std::uint32_t>(o.r2)} << 32) | r.begin;
      if (n == k) last = o.r2;
    }
    if (n < k) return -1;  // fewer than k within reach: the search must look farther
    std::sort(found.begin(), found.begin() + n);
    for (int j = 0; j < k; ++j) out[j] = static_cast<std::uint32_t>(found[static_cast<std::size_t>(j)]);
    return k;
  }

  // Larger buckets: ring r holds the buckets r steps away (the largest
  // coordinate difference). A node in ring r + 1 or beyond is at least
  // g = min over axes of (the node's distance to its bucket's far side plus
  // r buckets, or to its near side plus r buckets) + 1 cells away, so the
  // search stops once the k-th best is nearer than that.
  int nearest_buckets(const GridPoint& c, const std::int32_t (&base)[3], int k, std::uint32_t* out) const {
    struct Hit {
      std::uint64_t d2;
      std::uint32_t index;
      bool operator<(const Hit& o) const { return d2 != o.d2 ? d2 < o.d2 : index < o.index; }
    };
    std::array<Hit, kMaxK> best;
    int n = 0;
    if (k == 0) return 0;
    const std::int64_t side = std::int64_t{1} << shift_;
    std::int64_t within[3];
    for (int a = 0; a < 3; ++a) within[a] = c[static_cast<std::size_t>(a)] & (side - 1);
    // After ring r is read: the k-th best is final when it is nearer than
    // any node of ring r + 1 or beyond can be.
    auto settled = [&](std::int32_t r) {
      if (n < k) return false;
      std::int64_t gap = std::numeric_limits<std::int64_t>::max();
      for (int a = 0; a < 3; ++a) gap = std::min({gap, side * (r + 1) - within[a], within[a] + side * r + 1});
      return best[static_cast<std::size_t>(k - 1)].d2 < static_cast<std::uint64_t>(gap * gap);
    };
    std::uint32_t scanned = 0;
    std::int32_t ring = 0;
    // Ring r: the buckets whose largest offset is r. A column (dx, dy) of
    // the ring's square holds all its buckets dz = -r ... r when |dx| or
    // |dy| is r, else only dz = -r and r; the column's occupancy bits pick
    // the non-empty ones. The order within a ring changes nothing: the k
    // best are kept by (distance, index), and a ring is always read whole.
    for (;; ++ring) {
      const std::int32_t lo = base[2] - ring, hi = base[2] + ring;
      const unsigned span = ((2u << hi) - 1u) & ~((1u << lo) - 1u);  // bits lo ... hi
      const unsigned ends = (1u << lo) | (1u << hi);
      for (std::int32_t dx = -ring; dx <= ring; ++dx)
        for (std::int32_t dy = -ring; dy <= ring; ++dy) {
          const std::size_t column = static_cast<std::size_t>((base[0] + dx) * kSide + base[1] + dy);
          const bool edge = dx == -ring || dx == ring || dy == -ring || dy == ring;
          for (unsigned bits = occupied_[column] & (edge ? span : ends); bits != 0; bits &= bits - 1) {
            const Range& range = grid_[column * kSide + static_cast<std::size_t>(__builtin_ctz(bits))];
            // Crowded buckets (a cluster among sparse nodes) are left to the
            // k-d tree: the work per node stays bounded whatever the input.
            scanned += range.end - range.begin;
            if (scanned > kMaxScan) return -1;
            for (std::uint32_t j = range.begin; j < range.end; ++j) {
              std::uint64_t d2 = 0;
              for (std::size_t a = 0; a < 3; ++a) {
                const std::int64_t t = std::int64_t{cells_[j][a]} - std::int64_t{c[a]};
                d2 += static_cast<std::uint64_t>(t * t);
              }
              const Hit h{d2, j};
              if (n == k && !(h < best[static_cast<std::size_t>(k - 1)])) continue;
              int p = n < k ? n++ : k - 1;
              for (; p > 0 && h < best[static_cast<std::size_t>(p - 1)]; --p)
                best[static_cast<std::size_t>(p)] = best[static_cast<std::size_t>(p - 1)];
              best[static_cast<std::size_t>(p)] = h;
            }
          }
        }
      if (ring == kMargin || settled(ring)) break;
    }
    if (!settled(ring)) return -1;
    for (int j = 0; j < k; ++j) out[j] = best[static_cast<std::size_t>(j)].index;
    return k;
  }

  // Every offset within kMargin buckets in each coordinate, with its squared
  // length.
  static std::vector<Offset> cube() {
    std::vector<Offset> v;
    for (std::int32_t x = -kMargin; x <= kMargin; ++x)
      for (std::int32_t y = -kMargin; y <= kMargin; ++y)
        for (std::int32_t z = -kMargin; z <= kMargin; ++z)
          v.push_back({x, y, z, x * x + y * y + z * z});
    return v;
  }
  // Those within kMargin (Euclidean), by squared length.
  static const std::vector<Offset>& sphere() {
    static const std::vector<Offset> list = [] {
      std::vector<Offset> v = cube();
      v.erase(std::remove_if(v.begin(), v.end(), [](const Offset& o) { return o.r2 > kMargin * kMargin; }), v.end());
      std::stable_sort(v.begin(), v.end(), [](const Offset& a, const Offset& b) { return a.r2 < b.r2; });
      return v;
    }();
    return list;
  }

  // Fill the grid with the buckets of the block `key` and of the blocks
  // around it that lie within kMargin buckets of it.
  void load(std::uint64_t key) {
    for (std::uint32_t at : written_) grid_[at] = Range{0, 0};
    written_.clear();
    std::fill(occupied_.begin(), occupied_.end(), 0);
    loaded_ = key;
    const GridPoint b = morton_point(key, depth_ - bits_);
    const std::int32_t side = 1 << bits_;
    for (int a = 0; a < 3; ++a) origin_[a] = static_cast<std::int32_t>(b[static_cast<std::size_t>(a)]) * side - kMargin;
    const std::int64_t blocks_per_axis = std::int64_t{1} << (depth_ - bits_);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const std::int64_t p[3] = {std::int64_t{b[0]} + dx, std::int64_t{b[1]} + dy, std::int64_t{b[2]} + dz};
          if (p[0] < 0 || p[1] < 0 || p[2] < 0 || p[0] >= blocks_per_axis || p[1] >= blocks_per_axis ||
              p[2] >= blocks_per_axis)
            continue;
          const std::uint64_t nk = morton_key({static_cast<std::uint32_t>(p[0]), static_cast<std::uint32_t>(p[1]),
                                               static_cast<std::uint32_t>(p[2])},
                                              depth_ - bits_);
          const auto it = std::lower_bound(blocks_.begin(), blocks_.end(), nk,
                                           [](const Block& x, std::uint64_t v) { return x.key < v; });
          if (it == blocks_.end() || it->key != nk) continue;
          const std::uint32_t end = it + 1 == blocks_.end() ? static_cast<std::uint32_t>(keys_.size()) : (it + 1)->first;
          for (std::uint32_t j = it->first; j < end; ++j) {
            std::int32_t l[3];
            bool inside = true;
            for (int a = 0; a < 3; ++a) {
              l[a] = static_cast<std::int32_t>(cells_[j][static_cast<std::size_t>(a)] >> shift_) - origin_[a];
              inside = inside && l[a] >= 0 && l[a] < kSide;
            }
            if (!inside) continue;
            const auto at = static_cast<std::uint32_t>((l[0] * kSide + l[1]) * kSide + l[2]);
            Range& r = grid_[at];
            if (r.begin == r.end) {  // nodes of one bucket are consecutive
              r = Range{j, j + 1};
              written_.push_back(at);
              occupied_[at / kSide] = static_cast<std::uint16_t>(occupied_[at / kSide] | (1u << (at % kSide)));
            } else {
              r.end = j + 1;
            }
          }
        }
  }

  const std::vector<GridPoint>& cells_;
  const std::vector<std::uint64_t>& keys_;
  int shift_, depth_, bits_;  // depth_: of the buckets
  std::vector<Block> blocks_;
  std::vector<Range> grid_;
  std::vector<std::uint16_t> occupied_ = std::vector<std::uint16_t>(kSide * kSide, 0);  // per column (x, y): bit z
  std::vector<std::uint32_t> written_;
  std::uint64_t loaded_ = ~std::uint64_t{0};
  std::int32_t origin_[3] = {0, 0, 0};
};

}  // namespace hmc::detail
