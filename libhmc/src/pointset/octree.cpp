// SPDX-License-Identifier: AGPL-3.0-or-later
#include "pointset/octree.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <thread>

#include "entropy/huffman.hpp"
#include "entropy/paired.hpp"
#include "pointset/lattice_neighbours.hpp"
#include "pointset/plane_rank.hpp"
#include "util/error.hpp"
#include "util/helpers.hpp"
#include "util/kdtree.hpp"
#include "util/radix_sort.hpp"

namespace hmc::detail {

namespace {

// Three tree levels at a time: entry k of the table spreads the 9-bit Morton
// chunk k into its x, y and z bits (3 each), packed as x << 6 | y << 3 | z.
struct MortonChunks {
  std::array<std::uint16_t, 512> xyz{};
  MortonChunks() {
    for (std::uint32_t k = 0; k < 512; ++k) {
      std::uint32_t x = 0, y = 0, z = 0;
      for (std::uint32_t b = 0; b < 3; ++b) {
        const std::uint32_t c = k >> (3 * b);
        x |= ((c >> 2) & 1u) << b;
        y |= ((c >> 1) & 1u) << b;
        z |= (c & 1u) << b;
      }
      xyz[k] = static_cast<std::uint16_t>(x << 6 | y << 3 | z);
    }
  }
};

}  // namespace

GridPoint morton_point(std::uint64_t key, int q) {
  static const MortonChunks table;
  GridPoint p{0, 0, 0};
  // A key of depth q has no bits at or above 3q, so the last chunk may
  // reach past them.
  for (int b = 0; b < q; b += 3) {
    const std::uint32_t e = table.xyz[(key >> (3 * b)) & 511u];
    p[0] |= (e >> 6) << b;
    p[1] |= ((e >> 3) & 7u) << b;
    p[2] |= (e & 7u) << b;
  }
  return p;
}

namespace {

// The width in bits of the widest coordinate (at most 21).
int coordinate_width(std::uint32_t any) {
  int w = 0;
  while (w < 21 && (any >> w) != 0) ++w;
  return w;
}

// Sort keys that pack (x, y, z) in fields of w bits each, and unpack them.
std::vector<GridPoint> unpack_sorted(std::vector<std::uint64_t>& keys, int w, std::vector<std::uint64_t>& scratch) {
  radix_sort(keys, 3 * w, scratch);
  const std::uint64_t mask = (std::uint64_t{1} << w) - 1;
  std::vector<GridPoint> points(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i)
    points[i] = {static_cast<std::uint32_t>(keys[i] >> (2 * w)), static_cast<std::uint32_t>((keys[i] >> w) & mask),
                 static_cast<std::uint32_t>(keys[i] & mask)};
  return points;
}

// Points of depth q given by Morton keys, in canonical order. The keys are
// overwritten; scratch is working memory.
std::vector<GridPoint> canonical_from_morton(std::vector<std::uint64_t>& keys, int q,
                                             std::vector<std::uint64_t>& scratch) {
  for (auto& k : keys) {
    const GridPoint p = morton_point(k, q);
    k = (std::uint64_t{p[0]} << (2 * q)) | (std::uint64_t{p[1]} << q) | p[2];
  }
  return unpack_sorted(keys, q, scratch);
}

}  // namespace

void sort_canonical(std::vector<GridPoint>& points) {
  // Pack (x, y, z) into one key that sorts in canonical order, each field
  // as wide as the widest coordinate, so that the radix sort makes as few
  // passes as the coordinates need.
  std::uint32_t any = 0;
  for (const GridPoint& p : points) any |= p[0] | p[1] | p[2];
  const int w = coordinate_width(any);
  std::vector<std::uint64_t> keys(points.size()), scratch;
  for (std::size_t i = 0; i < points.size(); ++i)
    keys[i] = (std::uint64_t{points[i][0]} << (2 * w)) | (std::uint64_t{points[i][1]} << w) | points[i][2];
  points = unpack_sorted(keys, w, scratch);
}

namespace {

// The octree of a set given by its sorted Morton keys: for each depth, the
// occupancies of its nodes in Morton order (spec 8.1). The nodes themselves
// are rebuilt one depth at a time (nodes_at) where the ranked coder needs
// them: keeping every depth's would double the encoder's memory.
struct DepthOccupancy {
  std::vector<std::uint8_t> occupancy;
};

std::vector<DepthOccupancy> occupancies(const std::vector<std::uint64_t>& keys, int q) {
  std::vector<DepthOccupancy> out(static_cast<std::size_t>(q));
  for (int d = 0; d < q; ++d) {
    const int shift = 3 * (q - d);  // node key at depth d = key >> shift
    auto& level = out[static_cast<std::size_t>(d)];
    for (std::size_t i = 0; i < keys.size();) {
      const std::uint64_t node = keys[i] >> shift;
      std::uint8_t occ = 0;
      for (; i < keys.size() && (keys[i] >> shift) == node; ++i)
        occ = static_cast<std::uint8_t>(occ | (1u << ((keys[i] >> (shift - 3)) & 7u)));
      level.occupancy.push_back(occ);
    }
  }
  return out;
}

// The nodes of depth d in Morton order.
std::vector<std::uint64_t> nodes_at(const std::vector<std::uint64_t>& keys, int d, int q) {
  const int shift = 3 * (q - d);
  std::vector<std::uint64_t> nodes;
  for (std::uint64_t k : keys)
    if (nodes.empty() || nodes.back() != (k >> shift)) nodes.push_back(k >> shift);
  return nodes;
}

std::vector<std::uint64_t> sorted_keys(const std::vector<GridPoint>& points, int q) {
  std::vector<std::uint64_t> keys(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) keys[i] = morton_key(points[i], q);
  radix_sort(keys, 3 * q);
  return keys;
}

}  // namespace

namespace {

std::vector<std::uint8_t> write_octree(const std::vector<DepthOccupancy>& levels, int q) {
  BitWriter w;
  std::vector<HuffmanCode> codes;
  for (const auto& level : levels) {
    std::vector<std::uint64_t> freq(256, 0);
    for (std::uint8_t s : level.occupancy) ++freq[s];
    codes.push_back(HuffmanCode::from_frequencies(freq));
    codes.back().write(w);
  }
  for (int d = 0; d < q; ++d)
    for (std::uint8_t s : levels[static_cast<std::size_t>(d)].occupancy) codes[static_cast<std::size_t>(d)].encode(w, s);
  return w.finish();
}

}  // namespace

std::vector<std::uint8_t> encode_octree(const std::vector<GridPoint>& points, int q) {
  return write_octree(occupancies(sorted_keys(points, q), q), q);
}

namespace {

constexpr auto kPlainCoder = static_cast<std::uint8_t>(BaseCoder::octree);
constexpr auto kRankedCoder = static_cast<std::uint8_t>(BaseCoder::ranked);
// The gap weights the reference encoder tries at a ranked depth.
constexpr std::array<int, 10> kGapChoices{0, 1, 2, 3, 4, 6, 8, 11, 15, kFarRanking};
constexpr std::size_t kFarChoice = kGapChoices.size() - 1;  // kFarRanking's index
constexpr int kMaxNeighbours = 15;  // 4-bit field
// The neighbour counts the reference encoder tries (15 suits surfaces,
// whose nodes then take more decoded
// children into their points; 10 the interiors of volumes).
constexpr std::array<int, 2> kBaseNeighbours{10, 15};
constexpr int kCausalPoints = kMaxRankPoints;  // the most points a node is ranked by

// The nodes of one depth in Morton order, with the centres of their cells
// in doubled grid coordinates, and their nearest neighbours: looked up in a
// dense grid of cells around the node where the depth is dense enough
// (LatticeNeighbours), else, or when they lie farther, searched in a k-d
// tree over the centres (built on first use). Both give the same, exact
// neighbours. `nodes` must outlive the object.
class DepthNodes {
 public:
  DepthNodes(const DepthNodes&) = delete;  // search_ refers to cells_
  DepthNodes& operator=(const DepthNodes&) = delete;
  DepthNodes(const std::vector<std::uint64_t>& nodes, int d, int q) : d_(d), q_(q) {
    const std::int64_t h = std::int64_t{1} << (q - d);
    cells_.resize(nodes.size());
    centres_.resize(nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      cells_[i] = morton_point(nodes[i], d);
      for (std::size_t a = 0; a < 3; ++a) centres_[i][a] = 2 * std::int64_t{cells_[i][a]} * h + h;
    }
    // Cells one by one where the depth is dense (a surface crossing a block
    // of 8^3 cells occupies a few dozen); else buckets of 2^shift cells, the
    // smallest that hold one or two nodes each on a surface. The thresholds
    // are the fastest on the bunny and a 1M-point torus (points-only decode).
    int shift = 0;
    if (d > 0 && LatticeNeighbours::density(nodes, d, 0) < kDenseCells) {
      for (shift = 1; shift < d && LatticeNeighbours::density(nodes, d, shift) < kDenseBuckets; ++shift) {
      }
    }
    shift_ = shift;
    keys_ = &nodes;
    search_.lattice.emplace(cells_, nodes, d, shift);
  }

  /// The state of one thread's searches (nearest()): the lattice's loaded
  /// block and the k-d tree, built when first needed. DepthNodes keeps one
  /// for the calls without it; another thread needs its own (start_search).
  struct Search {
    std::optional<LatticeNeighbours> lattice;
    std::optional<KdTree<std::int64_t>> tree;
  };
  void start_search(Search& s) const { s.lattice.emplace(cells_, *keys_, d_, shift_); }

  /// The ranking of the children of node i (spec 8.2): by the plane through
  /// the k nearest node centres of the depth, the node's own included.
  /// Returns the node's context (spec 8.2): from how many children lie on
  /// the smaller side of the plane, 0 | 1 | 2-3 | 4 -> 0 | 1 | 2 | 3.
  /// `causal`, `quadric`: the causal points and the quadric, below.
  int rank(std::uint64_t node, std::size_t i, int neighbours, std::array<int, 8>& order, int gap = 0,
           const std::uint8_t* causal = nullptr, bool quadric = false) const {
    int context = 0;
    keys(node, i, neighbours, gap > 0, context, causal, quadric).order(0u, gap, order);
    return context;
  }

  /// rank() from node i's nearest nodes, found by nearest() beforehand.
  int rank(std::uint64_t node, std::size_t i, const std::uint32_t* near, int found, std::array<int, 8>& order, int gap,
           const std::uint8_t* causal, bool quadric) const {
    std::array<Doubled, kCausalPoints> nb{};
    const int count = expand(i, near, found, causal, nb);
    int context = 0;
    keys_of(node, nb, count, gap > 0, quadric, context).order(0u, gap, order);
    return context;
  }

  /// The keys that rank node i's children, with its context; `with_gaps`:
  /// for gap weights, the distances to the
  /// nearest neighbour other than the node itself (the first). `causal`:
  /// the occupancies of the depth's nodes before i
  /// (causal[j], j < i); a neighbour among them stands for the centres of
  /// its occupied children; `quadric`: rank by the quadric through them all.
  ChildKeys keys(std::uint64_t node, std::size_t i, int neighbours, bool with_gaps, int& context,
                 const std::uint8_t* causal = nullptr, bool quadric = false) const {
    std::array<Doubled, kCausalPoints> nb{};
    const int count = points(i, neighbours, causal, nb);
    return keys_of(node, nb, count, with_gaps, quadric, context);
  }

  /// The points that rank node i's children (the causal points with `causal`)
  /// into `nb`; returns their number.
  int points(std::size_t i, int neighbours, const std::uint8_t* causal, std::array<Doubled, kCausalPoints>& nb) const {
    Near near;
    const int found = nearest(i, neighbours, near);
    return expand(i, near, found, causal, nb);
  }

  /// The min(neighbours, number of nodes) node centres nearest to node i's
  /// (its own first), by (distance, index): indices into `near`; returns
  /// their number. The first k of them are the k nearest for any smaller k.
  using Near = std::array<std::uint32_t, kMaxNeighbours>;
  int nearest(std::size_t i, int neighbours, Near& near) const { return nearest(i, neighbours, near.data(), search_); }
  /// The same with another thread's search state (start_search()).
  int nearest(std::size_t i, int neighbours, std::uint32_t* near, Search& s) const {
    const int k = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(neighbours), centres_.size()));
    int found = s.lattice ? s.lattice->nearest(i, k, near) : -1;
    if (found < 0) {
      if (!s.tree) s.tree.emplace(centres_);
      std::array<KdTree<std::int64_t>::Hit, kMaxNeighbours> hits{};
      found = s.tree->nearest(centres_[i], k, hits.data());
      for (int j = 0; j < found; ++j) near[j] = hits[static_cast<std::size_t>(j)].index;
    }
    return found;
  }

  /// points() from the first `found` of node i's nearest nodes.
  int expand(std::size_t i, const Near& near, int found, const std::uint8_t* causal,
             std::array<Doubled, kCausalPoints>& nb) const {
    return expand(i, near.data(), found, causal, nb);
  }
  int expand(std::size_t i, const std::uint32_t* near, int found, const std::uint8_t* causal,
             std::array<Doubled, kCausalPoints>& nb) const {
    int count = 0;
    const std::int64_t h = std::int64_t{1} << (q_ - d_);
    for (int j = 0; j < found && count < kCausalPoints; ++j) {
      const std::uint32_t at = near[j];
      if (causal && at < i) {
        // Child c's centre, (2X + bit)·h + h/2 per axis (spec 8A.1).
        for (unsigned occ = causal[at]; occ != 0 && count < kCausalPoints; occ &= occ - 1) {
          const unsigned c = static_cast<unsigned>(__builtin_ctz(occ));
          auto& x = nb[static_cast<std::size_t>(count++)];
          for (std::size_t a = 0; a < 3; ++a)
            x[a] = static_cast<std::int32_t>((2 * std::int64_t{cells_[at][a]} + ((c >> (2 - a)) & 1)) * h + h / 2);
        }
        continue;
      }
      const auto& c = centres_[at];
      nb[static_cast<std::size_t>(count++)] = {static_cast<std::int32_t>(c[0]), static_cast<std::int32_t>(c[1]),
                                               static_cast<std::int32_t>(c[2])};
    }
    return count;
  }

  /// The keys of a node ranked by the points nb[0 .. count), with its context.
  ChildKeys keys_of(std::uint64_t node, const std::array<Doubled, kCausalPoints>& nb, int count, bool with_gaps,
                    bool quadric, int& context, ChildKeys* plane = nullptr) const {
    ChildKeys out(morton_point(node, d_), d_, q_, nb.data(), count, with_gaps, 1, quadric ? count : 0, plane);
    const int split = out.split();
    context = split <= 1 ? split : split <= 3 ? 2 : 3;
    return out;
  }

  /// The symbols of node i for every weight of kGapChoices, ranked by
  /// the plane (the first kGapChoices.size()) and by the quadric (the rest);
  /// `causal`: the depth's occupancies decoded before node i.
  std::array<std::uint8_t, 2 * kGapChoices.size()> symbols(std::uint64_t node, std::size_t i, unsigned occupancy,
                                                           int neighbours, const std::uint8_t* causal,
                                                           int& context) const {
    Near near;
    const int found = nearest(i, neighbours, near);
    return symbols(node, i, occupancy, near, found, causal, context);
  }
  /// The same from the first `found` of node i's nearest nodes (nearest()).
  std::array<std::uint8_t, 2 * kGapChoices.size()> symbols(std::uint64_t node, std::size_t i, unsigned occupancy,
                                                           const Near& near, int found, const std::uint8_t* causal,
                                                           int& context) const {
    std::array<std::uint8_t, 2 * kGapChoices.size()> out{};
    std::array<Doubled, kCausalPoints> nb{};
    const int count = expand(i, near, found, causal, nb);
    // The quadric's keys and, from the same work, the plane's.
    ChildKeys plane;
    const ChildKeys quadric = keys_of(node, nb, count, true, true, context, &plane);
    plane.symbols(0u, kGapChoices.data(), kGapChoices.size(), occupancy, out.data());
    quadric.symbols(0u, kGapChoices.data(), kGapChoices.size(), occupancy, out.data() + kGapChoices.size());
    return out;
  }

 private:
  static constexpr double kDenseCells = 16.0;    // nodes per occupied block of 8^3 cells
  static constexpr double kDenseBuckets = 64.0;   // nodes per occupied block of 8^3 buckets
  int d_, q_, shift_ = 0;
  const std::vector<std::uint64_t>* keys_ = nullptr;  // the depth's nodes (Morton keys), which outlive it
  std::vector<GridPoint> cells_;
  std::vector<KdTree<std::int64_t>::Point> centres_;
  mutable Search search_;
};

// Depths with fewer nodes are encoded on one thread (encode_ranked).
constexpr std::size_t kSplitNodes = 4096;

// The nearest nodes of a ranked depth's nodes, searched ahead on a helper
// thread while this one decodes (decode_nodes). A node's nearest nodes depend
// on the depth's node set alone; only the rest of its ranking (the causal
// points, the fit) waits for the symbols before it. The two threads claim
// nodes in order from one counter: the helper the next unclaimed one, at
// most kLead ahead of this thread, and this thread the node it is at when
// the helper has not claimed it yet; it waits only for a node the helper is
// searching at that moment. Each node is searched once, by one of them, so
// the result is that of one thread. Without a helper, every search is made
// here, node by node.
class SearchAhead {
 public:
  static constexpr std::size_t kLead = 4096;      // nodes the helper may be ahead (its ring of results)
  static constexpr std::size_t kMinNodes = 2048;  // smaller depths: not worth a thread
  SearchAhead(const DepthNodes& depth, std::size_t count, int neighbours, HelperBudget* helpers)
      : depth_(depth), count_(count), neighbours_(neighbours) {
    if (!helpers || count < kMinNodes) return;
    depth_.start_search(search_);
    near_.resize(kLead * kMaxNeighbours);
    found_.resize(kLead);
    stamp_ = std::make_unique<std::atomic<std::size_t>[]>(kLead);
    for (std::size_t s = 0; s < kLead; ++s) stamp_[s].store(0, std::memory_order_relaxed);
    job_ = helpers->try_run([this] { run(); });
  }
  SearchAhead(const SearchAhead&) = delete;
  SearchAhead& operator=(const SearchAhead&) = delete;
  ~SearchAhead() {
    stop_.store(true, std::memory_order_relaxed);
    if (job_.valid()) job_.wait();
  }

  /// Node i's nearest nodes (DepthNodes::nearest), for i = 0, 1, 2, ... in turn.
  int nearest(std::size_t i, DepthNodes::Near& near) {
    if (!job_.valid()) return depth_.nearest(i, neighbours_, near);
    at_.store(i, std::memory_order_release);  // nodes before i are done with: their slots are free
    std::size_t next = next_.load(std::memory_order_acquire);
    while (next <= i)
      if (next_.compare_exchange_weak(next, i + 1, std::memory_order_acq_rel))
        return depth_.nearest(i, neighbours_, near);
    // The helper has claimed node i: its result is there or about to be.
    const std::size_t slot = i % kLead;
    while (stamp_[slot].load(std::memory_order_acquire) != i + 1) {
      if (failed_.load(std::memory_order_acquire)) return depth_.nearest(i, neighbours_, near);
      std::this_thread::yield();
    }
    const int found = found_[slot];
    std::copy_n(near_.begin() + static_cast<std::ptrdiff_t>(slot * kMaxNeighbours), found, near.begin());
    return found;
  }

 private:
  void run() {
    while (!stop_.load(std::memory_order_relaxed)) {
      std::size_t j = next_.load(std::memory_order_acquire);
      if (j >= count_) return;
      if (j >= at_.load(std::memory_order_acquire) + kLead) {  // the ring is full
        std::this_thread::sleep_for(std::chrono::microseconds(50));
        continue;
      }
      if (!next_.compare_exchange_weak(j, j + 1, std::memory_order_acq_rel)) continue;
      const std::size_t slot = j % kLead;
      try {
        std::uint32_t* near = near_.data() + slot * kMaxNeighbours;
        found_[slot] = static_cast<std::int8_t>(depth_.nearest(j, neighbours_, near, search_));
      } catch (...) {  // out of memory for its k-d tree: the other thread searches for itself
        failed_.store(true, std::memory_order_release);
        return;
      }
      stamp_[slot].store(j + 1, std::memory_order_release);
    }
  }

  const DepthNodes& depth_;
  std::size_t count_;
  int neighbours_;
  DepthNodes::Search search_;  // the helper's
  std::vector<std::uint32_t> near_;  // kMaxNeighbours per slot; node j in slot j % kLead
  std::vector<std::int8_t> found_;
  std::unique_ptr<std::atomic<std::size_t>[]> stamp_;  // j + 1 once node j's result is in its slot
  std::atomic<std::size_t> next_{0};  // the first node neither thread has claimed
  std::atomic<std::size_t> at_{0};    // the node this thread is at
  std::atomic<bool> stop_{false}, failed_{false};
  std::future<void> job_;
};

// Coder 5 with `classes` contexts per ranked depth, from the plain and
// ranked symbols of every depth (ranked[d][i], context[d][i]) and each
// depth's gap weight and quadric flag: 5-bit weights and a flag before
// every table, each paired (spec 7.4) where that is smaller.
std::vector<std::uint8_t> write_ranked(const std::vector<DepthOccupancy>& levels, int q, int classes,
                                       const std::vector<std::vector<std::uint8_t>>& ranked_sym,
                                       const std::vector<std::vector<std::uint8_t>>& context, bool& any_ranked,
                                       const std::vector<int>& gaps, const std::vector<bool>& quadric,
                                       int neighbours) {
  any_ranked = false;
  std::vector<bool> ranked(static_cast<std::size_t>(q), false);
  // Per depth, its tables' symbol sequences in node order (one table at a
  // plain depth, `classes` at a ranked one).
  std::vector<std::vector<std::vector<std::uint32_t>>> seqs(static_cast<std::size_t>(q));
  std::vector<std::vector<std::uint64_t>> table_bits(static_cast<std::size_t>(q));  // each table's, unpaired
  for (int d = 0; d < q; ++d) {
    const auto sd = static_cast<std::size_t>(d);
    std::vector<std::uint64_t> plain_freq(256, 0);
    for (auto o : levels[sd].occupancy) ++plain_freq[o];
    std::vector<std::vector<std::uint64_t>> freq(static_cast<std::size_t>(classes), std::vector<std::uint64_t>(255, 0));
    for (std::size_t i = 0; i < ranked_sym[sd].size(); ++i)
      ++freq[std::min<std::size_t>(context[sd][i], static_cast<std::size_t>(classes - 1))][ranked_sym[sd][i]];
    const std::uint64_t plain_bits = coded_bits(plain_freq);
    std::vector<std::uint64_t> context_bits;
    for (const auto& f : freq)
      context_bits.push_back(table_and_symbols(f, HuffmanCode::from_frequencies(two_symbols_at_least(f))));
    // Rank only where it pays for the decoder's searches: 2% of the depth
    // (the depth's weight, and quadric flag, included).
    const auto header = static_cast<std::uint64_t>(kFarWeightBits + 1);
    const std::uint64_t ranked_bits = std::accumulate(context_bits.begin(), context_bits.end(), header);
    const bool use = !ranked_sym[sd].empty() && 100 * ranked_bits < 98 * plain_bits;
    table_bits[sd] = use ? std::move(context_bits) : std::vector<std::uint64_t>{plain_bits};
    ranked[sd] = use;
    any_ranked = any_ranked || use;
    if (use) {
      seqs[sd].resize(static_cast<std::size_t>(classes));
      for (std::size_t i = 0; i < ranked_sym[sd].size(); ++i)
        seqs[sd][std::min<std::size_t>(context[sd][i], static_cast<std::size_t>(classes - 1))].push_back(
            ranked_sym[sd][i]);
    } else {
      seqs[sd].emplace_back(levels[sd].occupancy.begin(), levels[sd].occupancy.end());
    }
  }
  // Pairing: each table where its paired form is smaller (at a ranked
  // depth, with a pair code of two symbols at least, so that every pair of
  // ranked nodes costs a bit).
  std::vector<std::vector<bool>> pair(static_cast<std::size_t>(q));
  for (int d = 0; d < q; ++d) {
    const auto sd = static_cast<std::size_t>(d);
    for (std::size_t j = 0; j < seqs[sd].size(); ++j) {
      const std::uint64_t plain = table_bits[sd][j];
      const std::uint64_t pairs = paired_bits(seqs[sd][j], ranked[sd] ? 255 : 256, TableForm::deltas, ranked[sd]);
      pair[sd].push_back(pairs < plain);
    }
  }
  BitWriter w;
  w.put(static_cast<std::uint32_t>(neighbours), 4);
  w.put(static_cast<std::uint32_t>(classes - 1), 2);
  std::vector<std::vector<TableCode>> codes(static_cast<std::size_t>(q));
  for (int d = 0; d < q; ++d) {
    const auto sd = static_cast<std::size_t>(d);
    w.put(ranked[sd] ? 1 : 0, 1);
    if (ranked[sd]) w.put(static_cast<std::uint32_t>(gaps[sd]), kFarWeightBits);
    if (ranked[sd]) w.put(quadric[sd] ? 1 : 0, 1);
    for (std::size_t j = 0; j < seqs[sd].size(); ++j) {
      codes[sd].push_back(TableCode::build(std::move(seqs[sd][j]), ranked[sd] ? 255 : 256, pair[sd][j], ranked[sd]));
      codes[sd].back().write(w, true, TableForm::deltas);
    }
  }
  for (int d = 0; d < q; ++d) {
    const auto sd = static_cast<std::size_t>(d);
    if (!ranked[sd]) {
      for (std::uint8_t s : levels[sd].occupancy) codes[sd][0].encode(w, s);
      continue;
    }
    for (std::size_t i = 0; i < ranked_sym[sd].size(); ++i)
      codes[sd][std::min<std::size_t>(context[sd][i], static_cast<std::size_t>(classes - 1))].encode(w, ranked_sym[sd][i]);
  }
  return w.finish();
}

// Whether ranking a large depth may pay, judged on a Morton-contiguous
// (so spatially compact) block of its nodes: 8,192 nodes indexed by
// themselves, the middle half ranked. An estimate (neighbours outside the
// block are missed), so that the encoder does not rank every node of a
// large depth to learn that ranking does not pay (a million random points:
// 12 times the plain coder's time without it). Every ranking the encoder
// may choose, each judged by its symbols' entropy: the best one
// decides (at the bunny's last depth the plane alone saves 0.4 %, the
// quadric with gap weights 17 %).
bool ranking_may_pay(const std::vector<std::uint64_t>& nodes, const DepthOccupancy& level, int d, int q) {
  constexpr std::size_t kBlock = 8192;
  const std::size_t n = nodes.size();
  if (n <= 2 * kBlock) return true;
  const std::size_t b0 = n / 2 - kBlock / 2;
  const std::vector<std::uint64_t> block(nodes.begin() + static_cast<std::ptrdiff_t>(b0),
                                         nodes.begin() + static_cast<std::ptrdiff_t>(b0 + kBlock));
  const DepthNodes depth(block, d, q);
  const std::uint8_t* decoded = level.occupancy.data() + b0;
  constexpr std::size_t kRankings = 2 * kGapChoices.size();  // every choice of encode_ranked
  std::vector<std::uint64_t> plain(256, 0), ranked(kRankings * 255, 0);
  int context = 0;
  for (std::size_t i = kBlock / 4; i < 3 * kBlock / 4; ++i) {
    const unsigned o = level.occupancy[b0 + i];
    ++plain[o];
    const auto s = depth.symbols(block[i], i, o, kBaseNeighbours[0], decoded, context);
    for (std::size_t g = 0; g < kRankings; ++g) ++ranked[g * 255 + s[g]];
  }
  double least = entropy_bits(plain.data(), plain.size());
  const double bound = 0.995 * least;
  for (std::size_t g = 0; g < kRankings; ++g)
    least = std::min(least, entropy_bits(ranked.data() + g * 255, 255));
  return least < bound;
}

// The ranked symbols of every depth for one neighbour count, with each
// depth's gap weight and quadric flag (spec 8.2) or weight alone (8.2).
struct RankedDepths {
  std::vector<std::vector<std::uint8_t>> symbols, context;  // [d][i]; empty where a depth is not ranked
  std::vector<int> gaps;
  std::vector<bool> quadric;
  explicit RankedDepths(std::size_t q) : symbols(q), context(q), gaps(q, 0), quadric(q, false) {}
};

// Node i's symbols and context for every choice (weight, plane or quadric)
// are all[i * kChoices + choice], ctx[i]; returns the cheapest choice open
// to the encoder, tables included, with the 4 contexts
// merged into 1, 2 or 4 as write_ranked may merge them, and (second) the
// cheapest of those without kFarRanking.
constexpr std::size_t kChoices = 2 * kGapChoices.size();  // plane, then quadric, for each weight
std::pair<std::size_t, std::size_t> cheapest_choice(const std::vector<std::uint8_t>& all,
                                                    const std::vector<std::uint8_t>& ctx) {
  std::vector<std::vector<std::uint64_t>> freq(kChoices, std::vector<std::uint64_t>(4 * 255, 0));
  for (std::size_t i = 0; i < ctx.size(); ++i)
    for (std::size_t g = 0; g < kChoices; ++g)
      ++freq[g][static_cast<std::size_t>(ctx[i]) * 255 + all[i * kChoices + g]];
  std::size_t chosen = 0, near = 0;
  double least = 0, least_near = 0;
  for (std::size_t g = 0; g < kChoices; ++g) {
    double bits = 0;
    for (std::size_t classes : {1, 2, 4}) {
      std::vector<std::vector<std::uint64_t>> merged(classes, std::vector<std::uint64_t>(255, 0));
      for (std::size_t c = 0; c < 4; ++c)
        for (std::size_t v = 0; v < 255; ++v) merged[std::min(c, classes - 1)][v] += freq[g][c * 255 + v];
      for (const auto& f : merged) bits += static_cast<double>(coded_bits(two_symbols_at_least(f)));
    }
    if (g == 0 || bits < least) least = bits, chosen = g;
    if (g % kGapChoices.size() != kFarChoice && (g == 0 || bits < least_near)) least_near = bits, near = g;
  }
  return {chosen, near};
}

// Coder 5: at every depth, the ranked symbols for the gap weight and
// ranking (plane or quadric) that make them cheapest, for each neighbour
// count of kBaseNeighbours; the smallest stream, and the far ranking where
// it makes that smaller still.
std::vector<std::uint8_t> encode_ranked(const std::vector<DepthOccupancy>& levels, const std::vector<std::uint64_t>& keys,
                                        int q, bool& any_ranked, HelperBudget* helpers) {
  const auto sq = static_cast<std::size_t>(q);
  const std::size_t counts = kBaseNeighbours.size();
  // by_count[n]: without the far ranking; with_far[n]: with it, where some
  // depth takes it (else empty).
  std::vector<RankedDepths> by_count(counts, RankedDepths(sq));
  std::vector<std::optional<RankedDepths>> with_far(counts);
  std::vector<std::vector<std::uint8_t>> all(counts);  // per count: node i's symbols for every choice, ctx below
  for (int d = 0; d < q; ++d) {
    const auto sd = static_cast<std::size_t>(d);
    const auto nodes = nodes_at(keys, d, q);
    const auto& occ = levels[sd].occupancy;
    if (!ranking_may_pay(nodes, levels[sd], d, q)) continue;
    const DepthNodes depth(nodes, d, q);
    // Each node's nearest nodes are searched once, for the largest count:
    // the smaller counts take their first ones.
    for (std::size_t n = 0; n < counts; ++n) {
      all[n].resize(occ.size() * kChoices);
      by_count[n].context[sd].resize(occ.size());
    }
    // The encoder knows every occupancy, so the nodes are independent: a
    // helper, where one is free, takes the second half (its own searches).
    split_range(helpers, nodes.size(), kSplitNodes, [&](std::size_t begin, std::size_t end) {
      DepthNodes::Search search;
      depth.start_search(search);
      for (std::size_t i = begin; i < end; ++i) {
        DepthNodes::Near near{};
        const int found = depth.nearest(i, kBaseNeighbours[counts - 1], near.data(), search);
        for (std::size_t n = 0; n < counts; ++n) {
          int c = 0;
          const int k = std::min(found, kBaseNeighbours[n]);
          const auto s = depth.symbols(nodes[i], i, occ[i], near, k, occ.data(), c);
          by_count[n].context[sd][i] = static_cast<std::uint8_t>(c);
          std::copy(s.begin(), s.end(), all[n].begin() + static_cast<std::ptrdiff_t>(i * kChoices));
        }
      }
    });
    for (std::size_t n = 0; n < counts; ++n) {
      RankedDepths& r = by_count[n];
      const auto& ctx = r.context[sd];
      const auto [chosen, near] = cheapest_choice(all[n], ctx);
      auto take = [&](RankedDepths& into, std::size_t choice) {
        into.gaps[sd] = kGapChoices[choice % kGapChoices.size()];
        into.quadric[sd] = choice >= kGapChoices.size();
        into.symbols[sd].resize(occ.size());
        for (std::size_t i = 0; i < nodes.size(); ++i) into.symbols[sd][i] = all[n][i * kChoices + choice];
      };
      if (chosen != near && !with_far[n]) with_far[n] = r;  // the depths before, as without it
      take(r, near);
      if (with_far[n]) {
        with_far[n]->context[sd] = ctx;
        take(*with_far[n], chosen);
      }
    }
  }
  // Each neighbour count with 1, 2 or 4 contexts: the smallest stream, but
  // more neighbours only where they save 1% of it (they make decoding
  // slower: on the bunny's base layer, 15 instead of 10 take points-only
  // decoding from 0.21 to 0.33 s for 0.3%). The neighbour count is chosen
  // without the far ranking, which is then kept where it makes the chosen
  // count's stream smaller.
  struct Written {
    std::vector<std::uint8_t> bytes;
    bool any = false;
  };
  auto keep = [&](Written& out, std::size_t n, const RankedDepths& r) {
    for (int classes : {1, 2, 4}) {
      bool any = false;
      auto bytes = write_ranked(levels, q, classes, r.symbols, r.context, any, r.gaps, r.quadric, kBaseNeighbours[n]);
      if (out.bytes.empty() || bytes.size() < out.bytes.size()) out = {std::move(bytes), any};
    }
  };
  Written best;
  std::size_t best_count = 0;
  for (std::size_t n = 0; n < counts; ++n) {
    Written smallest;
    keep(smallest, n, by_count[n]);
    if (best.bytes.empty() || 100 * smallest.bytes.size() < 99 * best.bytes.size())
      best = std::move(smallest), best_count = n;
  }
  if (with_far[best_count]) keep(best, best_count, *with_far[best_count]);
  any_ranked = best.any;
  return best.bytes;
}

// The number of children an occupancy byte names (a table: without a
// popcount instruction in the target, the builtin is a library call).
constexpr std::array<std::uint8_t, 256> kChildCount = [] {
  std::array<std::uint8_t, 256> t{};
  for (std::size_t i = 1; i < 256; ++i) t[i] = static_cast<std::uint8_t>(t[i / 2] + (i & 1));
  return t;
}();

// Both coders' symbol streams after their tables (spec 8.1, 8.2): ranked[d]
// says whether depth d sends ranked occupancies (coder 0: none).
// codes[d][j]: the table of depth d for context j (one at plain depths).
std::vector<GridPoint> decode_nodes(BitReader& in, int q, std::uint64_t n,
                                    std::vector<std::vector<TableCode>>& codes, const std::vector<bool>& ranked,
                                    int neighbours, const std::vector<int>& gaps, bool causal = false,
                                    const std::vector<bool>& quadric = {}, HelperBudget* helpers = nullptr) {
  std::vector<std::uint64_t> nodes{0}, next;
  std::vector<std::uint8_t> occupancies;  // coder 5: the depth's occupancies so far
  std::array<int, 8> order{};
  for (int d = 0; d < q; ++d) {
    next.clear();
    occupancies.clear();
    next.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(n, 8 * std::uint64_t{nodes.size()})));
    auto& table = codes[static_cast<std::size_t>(d)];
    std::optional<DepthNodes> depth;
    std::optional<SearchAhead> searches;  // after `depth`, which it reads: destroyed first
    if (ranked[static_cast<std::size_t>(d)]) {
      depth.emplace(nodes, d, q);
      searches.emplace(*depth, nodes.size(), neighbours, helpers);
    }
    DepthNodes::Near near{};
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      std::uint32_t occ = 0;
      if (depth) {
        const int found = searches->nearest(i, near);
        const int context = depth->rank(nodes[i], i, near.data(), found, order, gaps[static_cast<std::size_t>(d)],
                                        causal ? occupancies.data() : nullptr,
                                        causal && quadric[static_cast<std::size_t>(d)]);
        const std::uint32_t s = table[std::min<std::size_t>(static_cast<std::size_t>(context), table.size() - 1)].decode(in);
        occ = occupancy_of(order, s);
      } else if ((occ = table[0].decode(in)) == 0) {
        fail(Status::bad_layer, "BASE octree: empty occupancy at depth " + std::to_string(d));
      }
      if (next.size() + kChildCount[occ & 255u] > n)
        fail(Status::bad_layer, "BASE octree: more than the declared " + std::to_string(n) + " points");
      if (causal) occupancies.push_back(static_cast<std::uint8_t>(occ));
      const std::uint64_t first = nodes[i] << 3;
      for (; occ != 0; occ &= occ - 1) next.push_back(first | static_cast<std::uint32_t>(__builtin_ctz(occ)));
    }
    nodes.swap(next);
  }
  in.expect_end();
  if (nodes.size() != n)
    fail(Status::bad_layer, "BASE octree: " + std::to_string(nodes.size()) + " points, the header declares " +
                                std::to_string(n));
  return canonical_from_morton(nodes, q, next);  // next: spare capacity for the sort
}

// Coder 5: a ranked flag per depth and, at a ranked depth, its 5-bit
// weight, its quadric flag and a pairing flag before every table.
std::vector<GridPoint> decode_ranked(const std::uint8_t* data, std::size_t size, int q, std::uint64_t n, TableForm form,
                                     HelperBudget* helpers) {
  BitReader in(data, size, "BASE ranked octree");
  const int neighbours = static_cast<int>(in.get(4));
  const int classes = static_cast<int>(in.get(2)) + 1;
  std::vector<std::vector<TableCode>> codes(static_cast<std::size_t>(q));
  std::vector<bool> ranked;
  std::vector<int> gaps(static_cast<std::size_t>(q), 0);
  std::vector<bool> quadric(static_cast<std::size_t>(q), false);
  for (int d = 0; d < q; ++d) {
    ranked.push_back(in.get(1) == 1);
    if (ranked.back()) {
      const int gap = static_cast<int>(in.get(kFarWeightBits));
      if (gap > kFarRanking)
        fail(Status::bad_layer, "BASE ranked octree: ranking weight " + std::to_string(gap) + " at depth " +
                                    std::to_string(d) + " (at most 16)");
      gaps[static_cast<std::size_t>(d)] = gap;
      quadric[static_cast<std::size_t>(d)] = in.get(1) == 1;
    }
    const std::string what = "BASE ranked octree table for depth " + std::to_string(d);
    if (!ranked.back()) {
      codes[static_cast<std::size_t>(d)].push_back(TableCode::read(in, 256, true, what, form));
      continue;
    }
    for (int j = 0; j < classes; ++j) {
      codes[static_cast<std::size_t>(d)].push_back(
          TableCode::read(in, 255, true, what + " context " + std::to_string(j), form));
      // Every ranked node costs a bit, every pair of them when paired: its
      // nearest-neighbour search is paid for by the stream (spec 8.2).
      if (codes[static_cast<std::size_t>(d)].back().free())
        fail(Status::bad_layer, what + " context " + std::to_string(j) + ": a one-symbol code at a ranked depth");
    }
  }
  return decode_nodes(in, q, n, codes, ranked, neighbours, gaps, true, quadric, helpers);
}

}  // namespace

std::vector<std::uint8_t> encode_base(const std::vector<GridPoint>& points, int q, BaseCoder coder,
                                      HelperBudget* helpers) {
  if (!is_base_coder(static_cast<std::uint8_t>(coder)))
    fail(Status::invalid_argument, "BASE: the coders are 0 and 5");
  const auto keys = sorted_keys(points, q);
  const auto levels = occupancies(keys, q);
  auto plain = write_octree(levels, q);
  if (coder == BaseCoder::octree) {
    plain.insert(plain.begin(), kPlainCoder);
    return plain;
  }
  bool any_ranked = false;
  auto ranked = encode_ranked(levels, keys, q, any_ranked, helpers);
  std::vector<std::uint8_t> out;
  // A ranked coder only when it saves 1% of the layer: its searches cost
  // decoding time (measured with spec 0.15's coder 1: on a million random
  // points in a ball it saved 0.05% and made points-only decoding 25% slower).
  const bool use_ranked = any_ranked && 100 * ranked.size() < 99 * plain.size();
  out.push_back(use_ranked ? kRankedCoder : kPlainCoder);
  const auto& body = use_ranked ? ranked : plain;
  out.insert(out.end(), body.begin(), body.end());
  return out;
}

std::vector<GridPoint> decode_base(const std::uint8_t* data, std::size_t size, int q, std::uint64_t n, TableForm form,
                                   HelperBudget* helpers) {
  if (size < 1) fail(Status::bad_layer, "BASE: empty payload");
  if (data[0] == kPlainCoder) return decode_octree(data + 1, size - 1, q, n, form);
  if (data[0] == kRankedCoder) return decode_ranked(data + 1, size - 1, q, n, form, helpers);
  fail(Status::bad_layer, "BASE: unknown coder " + std::to_string(data[0]));
}

std::vector<GridPoint> decode_octree(const std::uint8_t* data, std::size_t size, int q, std::uint64_t n, TableForm form) {
  BitReader in(data, size, "BASE octree");
  std::vector<std::vector<TableCode>> codes(static_cast<std::size_t>(q));
  for (int d = 0; d < q; ++d)
    codes[static_cast<std::size_t>(d)].push_back(
        TableCode::read(in, 256, false, "BASE octree table for depth " + std::to_string(d), form));
  return decode_nodes(in, q, n, codes, std::vector<bool>(static_cast<std::size_t>(q), false), 0,
                      std::vector<int>(static_cast<std::size_t>(q), 0));
}

}  // namespace hmc::detail
