// SPDX-License-Identifier: AGPL-3.0-or-later
// Exact k-nearest-neighbour search in 3D with a deterministic tie rule:
// equal distances go to the smaller index (the position in the vector the
// tree was built from). Used with integer coordinates (exact squared
// distances) by the encoder, which clusters the input onto the points of a
// level of octree cells, and by the tests and benches.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace hmc::detail {

template <class T>
class KdTree {
 public:
  using Point = std::array<T, 3>;
  struct Hit {
    T d2{};
    std::uint32_t index = 0;
    bool operator<(const Hit& o) const { return d2 != o.d2 ? d2 < o.d2 : index < o.index; }
  };

  KdTree() = default;
  explicit KdTree(const std::vector<Point>& points) {
    entries_.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) entries_[i] = {points[i], static_cast<std::uint32_t>(i)};
    if (!entries_.empty()) build(0, static_cast<std::uint32_t>(entries_.size()));
  }

  std::size_t size() const { return entries_.size(); }

  /// The min(k, size) nearest points to `q`, ascending by (distance, index),
  /// written to `hits`; returns their number.
  int nearest(const Point& q, int k, Hit* hits) const {
    int count = 0;
    if (k > 0 && !nodes_.empty()) search(0, q, k, hits, count);
    return count;
  }

  /// The nearest point (the tree must not be empty).
  Hit nearest(const Point& q) const {
    Hit h;
    nearest(q, 1, &h);
    return h;
  }

  static T distance2(const Point& a, const Point& b) {
    T d2{};
    for (std::size_t i = 0; i < 3; ++i) d2 += (a[i] - b[i]) * (a[i] - b[i]);
    return d2;
  }

 private:
  static constexpr std::uint32_t kLeaf = 8;
  struct Entry {
    Point at;
    std::uint32_t index;
  };
  struct Node {
    Point lo, hi;
    std::uint32_t begin, end, right;  // right child (the left follows the node); 0 for a leaf
  };

  std::uint32_t build(std::uint32_t begin, std::uint32_t end) {
    const auto id = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    Node n{entries_[begin].at, entries_[begin].at, begin, end, 0};
    for (std::uint32_t i = begin; i < end; ++i)
      for (std::size_t a = 0; a < 3; ++a)
        n.lo[a] = std::min(n.lo[a], entries_[i].at[a]), n.hi[a] = std::max(n.hi[a], entries_[i].at[a]);
    if (end - begin > kLeaf) {
      std::size_t axis = 0;
      for (std::size_t a = 1; a < 3; ++a)
        if (n.hi[a] - n.lo[a] > n.hi[axis] - n.lo[axis]) axis = a;
      const std::uint32_t mid = begin + (end - begin) / 2;
      std::nth_element(entries_.begin() + begin, entries_.begin() + mid, entries_.begin() + end,
                       [axis](const Entry& x, const Entry& y) {
                         return x.at[axis] != y.at[axis] ? x.at[axis] < y.at[axis] : x.index < y.index;
                       });
      build(begin, mid);
      n.right = build(mid, end);
    }
    nodes_[id] = n;
    return id;
  }

  static T box_d2(const Node& n, const Point& q) {
    T d2{};
    for (std::size_t a = 0; a < 3; ++a) {
      const T t = q[a] < n.lo[a] ? n.lo[a] - q[a] : q[a] > n.hi[a] ? q[a] - n.hi[a] : T{};
      d2 += t * t;
    }
    return d2;
  }

  static void insert(const Hit& h, int k, Hit* hits, int& count) {
    if (count == k && !(h < hits[k - 1])) return;
    int j = count < k ? count++ : k - 1;
    for (; j > 0 && h < hits[j - 1]; --j) hits[j] = hits[j - 1];
    hits[j] = h;
  }

  void search(std::uint32_t id, const Point& q, int k, Hit* hits, int& count) const {
    const Node& n = nodes_[id];
    if (n.right == 0) {
      for (std::uint32_t i = n.begin; i < n.end; ++i) insert({distance2(entries_[i].at, q), entries_[i].index}, k, hits, count);
      return;
    }
    // Only strictly farther boxes are skipped: an equal distance with a
    // smaller index must still replace the last hit.
    std::uint32_t first = id + 1, second = n.right;
    T d_first = box_d2(nodes_[first], q), d_second = box_d2(nodes_[second], q);
    if (d_second < d_first) std::swap(first, second), std::swap(d_first, d_second);
    if (count < k || !(hits[k - 1].d2 < d_first)) search(first, q, k, hits, count);
    if (count < k || !(hits[k - 1].d2 < d_second)) search(second, q, k, hits, count);
  }

  std::vector<Entry> entries_;
  std::vector<Node> nodes_;
};

}  // namespace hmc::detail
