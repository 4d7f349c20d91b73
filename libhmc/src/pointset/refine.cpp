// SPDX-License-Identifier: AGPL-3.0-or-later
#include "pointset/refine.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <unordered_map>

#include "entropy/huffman.hpp"
#include "entropy/paired.hpp"
#include "pointset/octree.hpp"
#include "pointset/plane_rank.hpp"
#include "util/error.hpp"
#include "util/radix_sort.hpp"

namespace hmc::detail {

namespace {

constexpr int kMaxNeighbours = 15;        // 4-bit header field
constexpr int kQuadricNeighbours = 10;    // the encoder's quadric fit
constexpr int kFarNeighbours = 8;         // the encoder's second try of far ranking
constexpr int kMaxClasses = 4;            // 2-bit header field
constexpr int kMaxGap = 15;               // the largest weight below kFarRanking
constexpr std::uint32_t kAlphabet = 255;  // symbol i codes the i-th non-zero occupancy
const char* const kWhat = "refinement layer";

using Vec = std::array<std::int64_t, 3>;
using Point32 = Doubled;

std::uint64_t distance2(const Point32& p, const Vec& c) {
  std::uint64_t d2 = 0;
  for (std::size_t a = 0; a < 3; ++a) {
    const std::int64_t t = p[a] - c[a];
    d2 += static_cast<std::uint64_t>(t * t);
  }
  return d2;
}

// Exact k-nearest-neighbour search over the coarse points, in doubled grid
// coordinates (so that cell centres are integers). Equal distances go to the
// smaller canonical index, so every decoder picks the same neighbours.
class NeighbourIndex {
 public:
  struct Hit {
    std::uint64_t d2;
    std::uint32_t index;  // canonical index: breaks ties
    std::uint32_t slot;   // position in tree order: where the point is stored
    bool operator<(const Hit& o) const { return d2 != o.d2 ? d2 < o.d2 : index < o.index; }
  };

  explicit NeighbourIndex(const std::vector<GridPoint>& points) {
    entries_.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
      entries_[i] = {{static_cast<std::int32_t>(2 * points[i][0]), static_cast<std::int32_t>(2 * points[i][1]),
                      static_cast<std::int32_t>(2 * points[i][2])},
                     static_cast<std::uint32_t>(i)};
    if (!entries_.empty()) build(0, static_cast<std::uint32_t>(entries_.size()));
  }

  /// The min(k, size) nearest points to `c`, ascending; returns their number.
  int nearest(const Vec& c, int k, Hit* hits) const {
    int count = 0;
    if (k > 0 && !nodes_.empty()) search(0, c, k, hits, count);
    return count;
  }

  /// The hit for the point stored at `slot`, seen from `c`.
  Hit hit(std::uint32_t slot, const Vec& c) const { return {distance2(entries_[slot].at, c), entries_[slot].index, slot}; }
  const Point32& at(std::uint32_t slot) const { return entries_[slot].at; }

  /// Keeps the k smallest hits, sorted.
  static void insert(const Hit& h, int k, Hit* hits, int& count) {
    if (count == k && !(h < hits[k - 1])) return;
    int j = count < k ? count++ : k - 1;
    for (; j > 0 && h < hits[j - 1]; --j) hits[j] = hits[j - 1];
    hits[j] = h;
  }

 private:
  static constexpr std::uint32_t kLeaf = 8;
  // Points in tree order, so that a leaf's points are contiguous.
  struct Entry {
    Point32 at;           // doubled coordinates (< 2^22)
    std::uint32_t index;  // canonical index
  };
  struct Node {
    Point32 lo, hi;             // bounding box
    std::uint32_t begin, end;   // its points: entries_[begin, end)
    std::uint32_t right;        // right child; the left one follows the node; 0 for a leaf
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

  static std::uint64_t box_d2(const Node& n, const Vec& c) {
    std::uint64_t d2 = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      const std::int64_t t = c[a] < n.lo[a] ? n.lo[a] - c[a] : c[a] > n.hi[a] ? c[a] - n.hi[a] : 0;
      d2 += static_cast<std::uint64_t>(t * t);
    }
    return d2;
  }

  void search(std::uint32_t id, const Vec& c, int k, Hit* hits, int& count) const {
    const Node& n = nodes_[id];
    if (n.right == 0) {
      for (std::uint32_t i = n.begin; i < n.end; ++i) insert(hit(i, c), k, hits, count);
      return;
    }
    // Nearer child first. Only strictly farther boxes are skipped: a point
    // at the same distance with a smaller index must still replace the last hit.
    std::uint32_t first = id + 1, second = n.right;
    std::uint64_t d_first = box_d2(nodes_[first], c), d_second = box_d2(nodes_[second], c);
    if (d_second < d_first) std::swap(first, second), std::swap(d_first, d_second);
    if (count < k || d_first <= hits[k - 1].d2) search(first, c, k, hits, count);
    if (count < k || d_second <= hits[k - 1].d2) search(second, c, k, hits, count);
  }

  std::vector<Entry> entries_;
  std::vector<Node> nodes_;
};

// The coarse level as the coder sees it: which children of a node hold
// coarse points, and the ranking of the children from the plane through the
// node's nearest coarse points.
class CoarseLevel {
 public:
  static constexpr int kSpare = 4;
  static constexpr int kMaxCandidates = kMaxNeighbours + kSpare;

  /// Neighbour candidates handed down a chain of nodes: every coarse point
  /// not listed lies at least `reach` (doubled units) from `centre`.
  struct Candidates {
    Vec centre{};
    double reach = 0;
    int count = 0;
    std::array<std::uint32_t, kMaxCandidates> slot{};
  };

  CoarseLevel(const std::vector<GridPoint>& canonical, int q) : q_(q), index_(canonical) {
    keys_.resize(canonical.size());
    for (std::size_t i = 0; i < canonical.size(); ++i) keys_[i] = morton_key(canonical[i], q);
    radix_sort(keys_, 3 * q);
  }

  std::uint32_t size() const { return static_cast<std::uint32_t>(keys_.size()); }
  /// K, the number of neighbours that predict a node's children, and F, the
  /// number the quadric is fitted to (below 6: no quadric).
  void set_neighbours(int k, int fit = 0) {
    neighbours_ = k;
    fit_ = fit;
  }
  /// The gap weight of each depth's ranking (0: the plain
  /// ranking); `others`: last_keys() must also rank for other weights.
  void set_gaps(const std::vector<int>& gaps, bool others = false) {
    gaps_ = gaps;
    with_gaps_ = others || std::any_of(gaps.begin(), gaps.end(), [](int g) { return g > 0; });
  }
  /// With `on`, rank() also keeps the plane's keys of each node it ranks
  /// with a quadric (those of fit 0, the same neighbours) and the keys of
  /// its nearest neighbour alone (1 neighbour, no gaps): one traversal then
  /// gives the symbols of the three rankings.
  void set_twin(bool on) { twin_ = on; }
  /// The gap weight depth d ranks with.
  int gap(int d) const { return gaps_[static_cast<std::size_t>(d)]; }
  /// The keys of the node ranked last, and (set_twin) its plane's and its
  /// nearest point's keys.
  const ChildKeys& last_keys() const { return last_; }
  const ChildKeys& last_plane_keys() const { return last_plane_; }
  const ChildKeys& last_nearest_keys() const { return last_nearest_; }

  /// Boundaries of the coarse points of the eight children of a node at
  /// depth d holding keys_[c0, c1): child c holds keys_[b[c], b[c + 1]).
  void split(int d, std::uint64_t key, std::uint32_t c0, std::uint32_t c1, std::array<std::uint32_t, 9>& b) const {
    b[0] = c0;
    b[8] = c1;
    const int shift = 3 * (q_ - d - 1);
    for (std::size_t c = 1; c < 8; ++c) {
      const std::uint64_t first = ((key << 3) | c) << shift;
      b[c] = c0 == c1 ? c0
                      : static_cast<std::uint32_t>(
                            std::lower_bound(keys_.begin() + b[c - 1], keys_.begin() + c1, first) - keys_.begin());
    }
  }

  /// order[r] = the child of rank r: children holding coarse points first,
  /// then by distance of the child's centre to the plane fitted to the
  /// node's nearest coarse points, then by distance to their centroid, then
  /// by child number. `inherited` are the parent's candidates (or null);
  /// returns those for the node's children: `inherited` or `fresh`.
  const Candidates* rank(int d, std::uint64_t key, unsigned coarse_mask, const Candidates* inherited,
                         Candidates& fresh, std::array<int, 8>& order, int* split = nullptr) {
    const GridPoint p = morton_point(key, d);
    const std::int64_t h = std::int64_t{1} << (q_ - d);  // node side
    const Vec centre{2 * std::int64_t{p[0]} * h + h, 2 * std::int64_t{p[1]} * h + h, 2 * std::int64_t{p[2]} * h + h};
    int found = 0;
    const Candidates* handed = neighbours(centre, inherited, fresh, found);
    std::array<Point32, kMaxNeighbours> nb{};
    for (int i = 0; i < found; ++i)
      nb[static_cast<std::size_t>(i)] = index_.at(hits_[static_cast<std::size_t>(i)].slot);
    last_ = ChildKeys(p, d, q_, nb.data(), std::min(found, neighbours_), with_gaps_, 0, std::min(found, fit_),
                      twin_ ? &last_plane_ : nullptr);
    if (twin_) last_nearest_ = ChildKeys(p, d, q_, nb.data(), std::min(found, 1), false);
    last_.order(coarse_mask, gaps_[static_cast<std::size_t>(d)], order);
    if (split) *split = last_.split();
    return handed;
  }

 private:
  static constexpr double kInfinity = 1e300;

  // Fills hits_ with the max(K, F) nearest coarse points to `centre`. They
  // come from the inherited candidates when these provably hold them (deep
  // nodes move little from their parent), else from a search that keeps a
  // few spare points for the node's descendants. Only speed depends on the
  // candidates.
  const Candidates* neighbours(const Vec& centre, const Candidates* inherited, Candidates& fresh, int& count) {
    const int k = std::max(neighbours_, fit_);
    count = 0;
    if (k == 0) return nullptr;
    if (inherited) {
      for (int i = 0; i < inherited->count; ++i)
        NeighbourIndex::insert(index_.hit(inherited->slot[static_cast<std::size_t>(i)], centre), k, hits_.data(),
                               count);
      if (inherited->reach == kInfinity) return inherited;  // it lists every coarse point
      std::uint64_t shift2 = 0;
      for (std::size_t a = 0; a < 3; ++a)
        shift2 += static_cast<std::uint64_t>((centre[a] - inherited->centre[a]) * (centre[a] - inherited->centre[a]));
      // Points not listed are at least reach - shift away; the margin is far
      // above the rounding error of these doubles (values below 2^25).
      const double kth = std::sqrt(static_cast<double>(hits_[static_cast<std::size_t>(k) - 1].d2));
      if (kth + std::sqrt(static_cast<double>(shift2)) + 1e-6 < inherited->reach) return inherited;
    }
    std::array<NeighbourIndex::Hit, kMaxCandidates> all{};
    const int n = index_.nearest(centre, k + kSpare, all.data());
    fresh.centre = centre;
    fresh.count = n;
    fresh.reach = n < k + kSpare ? kInfinity : std::sqrt(static_cast<double>(all[static_cast<std::size_t>(n) - 1].d2));
    for (int i = 0; i < n; ++i) fresh.slot[static_cast<std::size_t>(i)] = all[static_cast<std::size_t>(i)].slot;
    count = std::min(n, k);
    std::copy_n(all.begin(), count, hits_.begin());
    return &fresh;
  }

  int q_;
  int neighbours_ = 0, fit_ = 0;
  std::vector<int> gaps_ = std::vector<int>(static_cast<std::size_t>(q_), 0);
  bool with_gaps_ = false, twin_ = false;
  ChildKeys last_{{0, 0, 0}, 0, 1, nullptr, 0, false}, last_plane_, last_nearest_;
  NeighbourIndex index_;
  std::vector<std::uint64_t> keys_;  // Morton keys of the coarse points, ascending
  std::array<NeighbourIndex::Hit, kMaxNeighbours> hits_{};
};

void check_grid(const std::vector<GridPoint>& points, int q, const char* name) {
  for (const GridPoint& p : points)
    if ((p[0] | p[1] | p[2]) >> q)
      fail(Status::invalid_argument, std::string(kWhat) + ": a " + name + " point lies outside the 2^" +
                                         std::to_string(q) + " grid");
}

void check_coarse(const std::vector<GridPoint>& coarse, int q) {
  if (q < 1 || q > 21) fail(Status::invalid_argument, std::string(kWhat) + ": q must be 1..21");
  if (coarse.empty()) fail(Status::invalid_argument, std::string(kWhat) + ": the coarse level is empty");
  if (std::uint64_t{coarse.size()} >= (std::uint64_t{1} << 32) - 1)
    fail(Status::invalid_argument, std::string(kWhat) + ": too many coarse points");
  check_grid(coarse, q, "coarse");
  for (std::size_t i = 1; i < coarse.size(); ++i)
    if (!(coarse[i - 1] < coarse[i]))
      fail(Status::invalid_argument, std::string(kWhat) + ": coarse points not distinct and in canonical order");
}

// The nodes of the added points' octree are visited depth first (a node,
// then the subtrees of its occupied children in child order): the decoder
// then keeps one path of nodes, and consecutive nodes share neighbours.

// ---------------------------------------------------------------- encoder

// One coded node: its depth, how many of its children hold coarse points
// (the context), its symbol, and whether the fitted plane crosses it (at
// least two children on each side: the plane context).
struct Symbol {
  std::uint8_t depth, weight, index, plane;
};

// The plane context (spec 8A.1) from the count of children on the smaller
// side of the plane.
std::uint8_t plane_context(int split) { return split >= 2 ? 1 : 0; }

// The symbols of the coarse level's ranking. With `gaps`, it also counts,
// per gap weight gaps[j], the symbols that ranking would give:
// counts[j].row((d * 9 + w) * 2 + x)[s], as encode_impl's freq
// (the coarse level must have been set to rank for other weights), and
// keeps them: other[i * gaps.size() + j] for the i-th symbol.
//
// Counts: q · 18 rows of 255 counts, of which a layer uses a few dozen; only
// those are stored (dense, all weights and a twin's, they took 7 MB of
// rocker_arm's 16 MB encoding peak). A count never exceeds the nodes of one
// depth, which each hold an added point, so 32 bits hold it (encode_impl
// admits fewer than 2^32 − 1 added points).
class Counts {
 public:
  explicit Counts(std::size_t rows) : at_(rows, kNone) {}
  void add(std::size_t row, std::size_t symbol) {
    if (at_[row] == kNone) {
      at_[row] = data_.size();
      data_.resize(data_.size() + kAlphabet, 0);
    }
    ++data_[at_[row] + symbol];
  }
  /// The row's kAlphabet counts, or nullptr when all are 0.
  const std::uint32_t* row(std::size_t r) const { return at_[r] == kNone ? nullptr : data_.data() + at_[r]; }

 private:
  static constexpr std::size_t kNone = ~std::size_t{0};
  std::vector<std::size_t> at_;       // per row: where its counts start in data_, or kNone
  std::vector<std::uint32_t> data_;
};
// Row r of a frequency list (encode_impl's freq) or of Counts; nullptr for
// a row of Counts that holds none.
const std::uint64_t* row_of(const std::vector<std::uint64_t>& freq, std::size_t r) {
  return freq.data() + r * kAlphabet;
}
const std::uint32_t* row_of(const Counts& counts, std::size_t r) { return counts.row(r); }

class Traversal {
 public:
  static constexpr std::size_t kMaxWeights = kFarRanking + 1;  // weights 0 ... kFarRanking, each at most once

  /// `twin` (the coarse level set_twin()): the traversal also keeps the
  /// plane's symbols, counts and others, which swap_twin() trades for its
  /// own, and the nearest neighbour's symbols (nearest()).
  Traversal(CoarseLevel& coarse, const std::vector<std::uint64_t>& added, int q, const std::vector<int>& gaps = {},
            bool twin = false)
      : coarse_(coarse), added_(added), q_(q), gaps_(gaps), twin_(twin) {
    if (gaps.size() > kMaxWeights) fail(Status::internal_error, "refinement: too many ranking weights to count");
    counts.assign(gaps.size(), Counts(static_cast<std::size_t>(q) * 18));
    if (twin) twin_counts_ = counts;
    visit(0, 0, 0, coarse.size(), 0, static_cast<std::uint32_t>(added.size()), nullptr);
  }
  std::vector<Symbol> symbols;
  std::vector<Counts> counts;
  std::vector<std::uint8_t> other;

  /// Trades symbols, counts and other with the plane's (a twin traversal).
  void swap_twin() {
    symbols.swap(twin_symbols_);
    counts.swap(twin_counts_);
    other.swap(twin_other_);
  }
  /// The traversal ranked by the nearest neighbour alone, without weights to
  /// count (a twin traversal's; its symbols are moved out).
  Traversal nearest() { return Traversal(coarse_, added_, q_, std::move(nearest_symbols_)); }

  /// Turns `symbols` into those a traversal ranked with weight chosen[d] at
  /// depth d would give, where each chosen[d] is the weight this one ranked
  /// depth d with (`ranked`) or one of `gaps`: the same nodes in the same
  /// order, each node's symbol the one its keys give for that weight. False
  /// (and `symbols` untouched) when some weight is neither.
  bool rank_with(const std::vector<int>& ranked, const std::vector<int>& chosen) {
    std::vector<int> column(chosen.size(), -1);  // per depth: -1 the ranked symbol, else the index in gaps_
    for (std::size_t d = 0; d < chosen.size(); ++d) {
      if (chosen[d] == ranked[d]) continue;
      const auto at = std::find(gaps_.begin(), gaps_.end(), chosen[d]);
      if (at == gaps_.end()) return false;
      column[d] = static_cast<int>(at - gaps_.begin());
    }
    for (std::size_t i = 0; i < symbols.size(); ++i) {
      const int j = column[symbols[i].depth];
      if (j >= 0) symbols[i].index = other[i * gaps_.size() + static_cast<std::size_t>(j)];
    }
    return true;
  }

 private:
  void visit(int d, std::uint64_t key, std::uint32_t c0, std::uint32_t c1, std::uint32_t a0, std::uint32_t a1,
             const CoarseLevel::Candidates* inherited) {
    std::array<std::uint32_t, 9> cb{}, ab{};
    coarse_.split(d, key, c0, c1, cb);
    const int shift = 3 * (q_ - d - 1);
    ab[0] = a0;
    for (std::uint32_t c = 0, i = a0; c < 8; ++c) {
      while (i < a1 && ((added_[i] >> shift) & 7u) == c) ++i;
      ab[c + 1] = i;
    }
    unsigned mask = 0, occ = 0;
    for (std::size_t c = 0; c < 8; ++c) {
      if (cb[c + 1] > cb[c]) mask |= 1u << c;
      if (ab[c + 1] > ab[c]) occ |= 1u << c;
    }
    CoarseLevel::Candidates fresh;
    std::array<int, 8> order{};
    int split = 0;
    const CoarseLevel::Candidates* handed = coarse_.rank(d, key, mask, inherited, fresh, order, &split);
    const Symbol symbol{static_cast<std::uint8_t>(d), static_cast<std::uint8_t>(popcount8(mask)),
                        ranked_symbol(order, occ), plane_context(split)};
    symbols.push_back(symbol);
    const std::size_t row = (static_cast<std::size_t>(d) * 9 + symbol.weight) * 2 + symbol.plane;
    std::array<std::uint8_t, kMaxWeights> s{};
    coarse_.last_keys().symbols(mask, gaps_.data(), gaps_.size(), occ, s.data());
    for (std::size_t j = 0; j < gaps_.size(); ++j) {
      counts[j].add(row, s[j]);
      other.push_back(s[j]);
    }
    if (twin_) {
      // The plane's: the same node, context and plane context (the split is
      // the plane's in both), its own symbols.
      const ChildKeys& plane = coarse_.last_plane_keys();
      Symbol mine = symbol;
      mine.index = plane.symbol(mask, coarse_.gap(d), occ);
      twin_symbols_.push_back(mine);
      // The nearest point's: no plane (its split is 0), no weight.
      nearest_symbols_.push_back(
          {symbol.depth, symbol.weight, coarse_.last_nearest_keys().symbol(mask, 0, occ), plane_context(0)});
      plane.symbols(mask, gaps_.data(), gaps_.size(), occ, s.data());
      for (std::size_t j = 0; j < gaps_.size(); ++j) {
        twin_counts_[j].add(row, s[j]);
        twin_other_.push_back(s[j]);
      }
    }
    if (d + 1 == q_) return;
    for (std::size_t c = 0; c < 8; ++c)
      if (occ & (1u << c)) visit(d + 1, (key << 3) | c, cb[c], cb[c + 1], ab[c], ab[c + 1], handed);
  }

  CoarseLevel& coarse_;
  const std::vector<std::uint64_t>& added_;
  int q_;
  std::vector<int> gaps_;
  bool twin_ = false;
  std::vector<Symbol> twin_symbols_;
  std::vector<Counts> twin_counts_;
  std::vector<std::uint8_t> twin_other_;
  std::vector<Symbol> nearest_symbols_;
  // nearest(): a traversal's symbols, known without visiting.
  Traversal(CoarseLevel& coarse, const std::vector<std::uint64_t>& added, int q, std::vector<Symbol>&& known)
      : symbols(std::move(known)), coarse_(coarse), added_(added), q_(q) {}
};

// Which table each (depth, class, plane context) slot uses. Per class and
// plane context, consecutive depths share a table when that costs fewer bits
// than a table of their own. Slot (d, k, x) is (d * classes + k) * planes + x,
// the order of the stream; planes is 1 or 2 (plane contexts, coder 7 only).
struct TablePlan {
  int classes = 1, planes = 1;
  std::vector<int> gaps;  // per depth: the ranking weight (all 0 with coder 0)
  int fit = 0;            // when above 0: the quadric's neighbours (coder 7)
  std::vector<bool> fresh;                       // [slot]: a table is sent
  std::vector<int> table;                        // [slot]: the table used, -1 for none
  std::vector<std::vector<std::uint64_t>> freq;  // per table
  std::vector<bool> paired;                      // per table: the paired form (spec 7.4); empty: none
  std::uint64_t bits = 0;                        // header, tables and symbols
};

// Whether some depth ranks far from the neighbours.
bool any_far(const std::vector<int>& gaps) {
  return std::any_of(gaps.begin(), gaps.end(), [](int g) { return g == kFarRanking; });
}

// Whether the depths' gap weights differ (coder 7's per-depth form).
bool per_depth(const std::vector<int>& gaps) {
  return std::any_of(gaps.begin(), gaps.end(), [&](int g) { return g != gaps[0]; });
}

// The coder of a plan: 0 (the short header) when it needs none of the full
// header's fields, else 7.
RefineCoder coder_of(const TablePlan& p) {
  const bool plain = p.planes == 1 && p.fit == 0 && p.paired.empty() &&
                     std::all_of(p.gaps.begin(), p.gaps.end(), [](int g) { return g == 0; });
  return plain ? RefineCoder::conditional_octree : RefineCoder::ranked_octree;
}

// The bits of coder 7's header fields past coder 0's (planes, fit, the flag
// and the weights; the pair flags are counted per table).
std::uint64_t full_header_bits(const std::vector<int>& gaps) {
  return 6 + static_cast<std::uint64_t>(kFarWeightBits) * (per_depth(gaps) ? gaps.size() : 1);
}

// coded_bits() of the frequency vectors seen before. The plans of one
// layer meet the same sums again and again: a class's rows are the same
// for every larger class count, a depth's rows the same for every ranking
// that chose the same weight there (horse, 4 levels: 38,449 calls, 15,242
// distinct vectors). Keyed by the alphabet size and the nonzero entries.
class CodedBitsMemo {
 public:
  std::uint64_t operator()(const std::vector<std::uint64_t>& f) {
    key_.assign(1, f.size());
    for (std::size_t s = 0; s < f.size(); ++s)
      if (f[s]) key_.push_back(s), key_.push_back(f[s]);
    const auto it = memo_.find(key_);
    if (it != memo_.end()) return it->second;
    const std::uint64_t bits = coded_bits(f);
    memo_.emplace(key_, bits);
    return bits;
  }

 private:
  struct Hash {
    std::size_t operator()(const std::vector<std::uint64_t>& v) const {
      std::uint64_t h = 0x9E3779B97F4A7C15ull;
      for (std::uint64_t x : v) h = (h ^ x) * 0x100000001B3ull;
      return static_cast<std::size_t>(h ^ (h >> 29));
    }
  };
  std::vector<std::uint64_t> key_;
  std::unordered_map<std::vector<std::uint64_t>, std::uint64_t, Hash> memo_;
};

// freq[((d * 9 + w) * 2 + x) * kAlphabet + s]: symbols s at depth d of
// nodes with w children holding coarse points and plane context x.
template <class Freq>
TablePlan plan_tables(const Freq& freq, int q, int classes, int planes,
                      const std::vector<int>& gaps, int fit, CodedBitsMemo& coded) {
  TablePlan plan;
  plan.classes = classes;
  plan.planes = planes;
  plan.gaps = gaps;
  plan.fit = fit;
  const auto slots = static_cast<std::size_t>(q * classes * planes);
  plan.fresh.assign(slots, false);
  plan.table.assign(slots, -1);
  // Header fields (neighbours, classes; coder 7: planes, fit, and one
  // weight or one per depth), then one flag per slot (and, coder 7, one per
  // table: added at the end).
  const RefineCoder coder = coder_of(plan);
  const bool full = coder == RefineCoder::ranked_octree;
  plan.bits = 6 + slots + (full ? full_header_bits(gaps) : 0);
  std::vector<std::uint64_t> f(kAlphabet);
  for (int k = 0; k < classes; ++k)
    for (int x = 0; x < planes; ++x) {
      int current = -1;
      std::uint64_t current_bits = 0;
      for (int d = 0; d < q; ++d) {
        std::fill(f.begin(), f.end(), 0);
        bool used = false;
        for (int w = k; w <= (k == classes - 1 ? 8 : k); ++w)
          for (int y = 0; y < 2; ++y) {
            if (planes == 2 && y != x) continue;
            const std::size_t row =
                (static_cast<std::size_t>(d) * 9 + static_cast<std::size_t>(w)) * 2 + static_cast<std::size_t>(y);
            const auto* counts = row_of(freq, row);
            if (!counts) continue;
            for (std::size_t s = 0; s < kAlphabet; ++s) {
              const std::uint64_t v = counts[s];
              f[s] += v;
              used = used || v;
            }
          }
        const auto slot = static_cast<std::size_t>((d * classes + k) * planes + x);
        plan.table[slot] = current;
        if (!used) continue;
        const std::uint64_t alone = coded(f);
        if (current >= 0) {
          std::vector<std::uint64_t> merged = plan.freq[static_cast<std::size_t>(current)];
          for (std::size_t s = 0; s < kAlphabet; ++s) merged[s] += f[s];
          const std::uint64_t together = coded(merged);
          if (together - current_bits <= alone) {
            plan.freq[static_cast<std::size_t>(current)] = std::move(merged);
            current_bits = together;
            continue;
          }
          plan.bits += current_bits;
        }
        current = static_cast<int>(plan.freq.size());
        plan.freq.push_back(f);
        current_bits = alone;
        plan.fresh[slot] = true;
        plan.table[slot] = current;
      }
      if (current >= 0) plan.bits += current_bits;
    }
  if (full) plan.bits += plan.freq.size();
  return plan;
}

// The table of each node, by slot (spec 8A.1: depth, class, plane context).
int table_of(const Symbol& s, const TablePlan& plan) {
  const int k = std::min<int>(s.weight, plan.classes - 1);
  const int x = plan.planes == 2 ? s.plane : 0;
  return plan.table[static_cast<std::size_t>((s.depth * plan.classes + k) * plan.planes + x)];
}

// The symbols of each table in the order of the nodes that use them.
std::vector<std::vector<std::uint32_t>> sequences(const std::vector<Symbol>& symbols, const TablePlan& plan) {
  std::vector<std::vector<std::uint32_t>> out(plan.freq.size());
  for (const Symbol& s : symbols) out[static_cast<std::size_t>(table_of(s, plan))].push_back(s.index);
  return out;
}

// Pairs the symbols of the tables where that is smaller (spec 7.4, coder
// 7's pair flags); returns false, leaving the plan as it is, when it would
// not make the layer smaller.
bool pair_tables(const std::vector<Symbol>& symbols, TablePlan& plan, bool force = false) {
  const auto seqs = sequences(symbols, plan);
  std::vector<bool> paired(plan.freq.size(), false);
  // A coder 0 plan becomes coder 7: its header fields and a flag per table.
  std::uint64_t bits = plan.bits;
  if (coder_of(plan) == RefineCoder::conditional_octree) bits += full_header_bits(plan.gaps) + plan.freq.size();
  bool any = false;
  for (std::size_t t = 0; t < seqs.size(); ++t) {
    const std::uint64_t plain = coded_bits(plan.freq[t]);
    const std::uint64_t pairs = paired_bits(seqs[t], kAlphabet, TableForm::deltas);
    if (pairs < plain) {
      paired[t] = any = true;
      bits = bits - plain + pairs;
    }
  }
  if (!force && (!any || (bits + 7) / 8 >= (plan.bits + 7) / 8)) return false;
  plan.paired = std::move(paired);
  plan.bits = bits;
  return true;
}

std::vector<std::uint8_t> write_layer(const std::vector<Symbol>& symbols, const TablePlan& plan, int neighbours) {
  // Coder 7 sends a flag per table; without a pairing plan, all 0.
  const bool flagged = coder_of(plan) == RefineCoder::ranked_octree;
  auto seqs = sequences(symbols, plan);
  std::vector<TableCode> codes;
  for (std::size_t t = 0; t < seqs.size(); ++t)
    codes.push_back(TableCode::build(std::move(seqs[t]), kAlphabet, !plan.paired.empty() && plan.paired[t]));
  BitWriter w;
  w.put(static_cast<std::uint32_t>(neighbours), 4);
  w.put(static_cast<std::uint32_t>(plan.classes - 1), 2);
  if (flagged) {
    w.put(static_cast<std::uint32_t>(plan.planes - 1), 1);
    const bool varies = per_depth(plan.gaps);
    w.put(static_cast<std::uint32_t>(plan.fit), 4);
    w.put(varies ? 1u : 0u, 1);
    if (!varies) w.put(static_cast<std::uint32_t>(plan.gaps[0]), kFarWeightBits);
    else
      for (int g : plan.gaps) w.put(static_cast<std::uint32_t>(g), kFarWeightBits);
  }
  for (std::size_t slot = 0; slot < plan.fresh.size(); ++slot) {
    w.put(plan.fresh[slot] ? 1u : 0u, 1);
    if (plan.fresh[slot]) codes[static_cast<std::size_t>(plan.table[slot])].write(w, flagged, TableForm::deltas);
  }
  for (const Symbol& s : symbols) codes[static_cast<std::size_t>(table_of(s, plan))].encode(w, s.index);
  return w.finish();
}

// The gap weight of each depth that forced parameters ask for.
std::vector<int> gaps_of(const RefinementParams& p, int q) {
  if (!p.depth_gaps.empty()) return p.depth_gaps;
  return std::vector<int>(static_cast<std::size_t>(q), p.gap);
}

RefinementLayer encode_impl(const std::vector<GridPoint>& coarse_in, const std::vector<GridPoint>& added_in, int q,
                            const RefinementParams* forced, bool all_coders, bool fast = false) {
  if (q < 1 || q > 21) fail(Status::invalid_argument, std::string(kWhat) + ": q must be 1..21");
  // The coarse level's canonical order breaks neighbour ties; accept any order here.
  std::vector<GridPoint> coarse = coarse_in;
  sort_canonical(coarse);
  check_coarse(coarse, q);
  check_grid(added_in, q, "added");
  if (std::uint64_t{added_in.size()} >= (std::uint64_t{1} << 32) - 1)
    fail(Status::invalid_argument, std::string(kWhat) + ": too many added points");
  if (forced && (forced->neighbours < 0 || forced->neighbours > kMaxNeighbours || forced->classes < 1 ||
                 forced->classes > kMaxClasses || forced->gap < 0 ||
                 (forced->gap > kMaxGap && forced->gap != kFarRanking) || forced->fit < 0 ||
                 forced->fit > kMaxNeighbours ||
                 (!forced->depth_gaps.empty() && forced->depth_gaps.size() != static_cast<std::size_t>(q)) ||
                 std::any_of(forced->depth_gaps.begin(), forced->depth_gaps.end(),
                             [](int g) { return g < 0 || (g > kMaxGap && g != kFarRanking); })))
    fail(Status::invalid_argument, std::string(kWhat) + ": parameters out of range");
  if (added_in.empty()) {
    if (!forced) return {static_cast<std::uint8_t>(RefineCoder::conditional_octree), {}};
    TablePlan p;
    p.planes = forced->plane_contexts ? 2 : 1;
    p.gaps = gaps_of(*forced, q);
    p.fit = forced->fit;
    if (forced->paired) p.paired.push_back(false);
    return {static_cast<std::uint8_t>(coder_of(p)), {}};
  }

  std::vector<std::uint64_t> added(added_in.size());
  for (std::size_t i = 0; i < added.size(); ++i) added[i] = morton_key(added_in[i], q);
  radix_sort(added, 3 * q);
  for (std::size_t i = 1; i < added.size(); ++i)
    if (added[i] == added[i - 1]) fail(Status::invalid_argument, std::string(kWhat) + ": added points not distinct");
  for (std::uint64_t key : added)
    if (std::binary_search(coarse.begin(), coarse.end(), morton_point(key, q)))
      fail(Status::invalid_argument, std::string(kWhat) + ": an added point is also a coarse point");

  // Plane contexts double the tables; they are kept only when the stream
  // they give is smaller.
  std::vector<int> plane_choices{1};
  if (forced) plane_choices = {forced->plane_contexts ? 2 : 1};
  else if (all_coders) plane_choices = {1, 2};
  CoarseLevel level(coarse, q);
  // The smallest plan for one ranking (neighbours, gap weights): plan.bits
  // is the layer's exact length, so plans compare in whole bytes, and only
  // the best is written. On a tie the earlier one stays (fewer tables, no
  // weights).
  const auto bytes_of = [](const TablePlan& p) { return (p.bits + 7) / 8; };
  CodedBitsMemo coded;  // this layer's plans only
  const auto plan_of = [&](const auto& freq, const std::vector<int>& gaps, int fit) {
    std::optional<TablePlan> plan;
    for (int planes : plane_choices)
      for (int classes = 1; classes <= kMaxClasses; ++classes) {
        if (forced && classes != forced->classes) continue;
        TablePlan p = plan_tables(freq, q, classes, planes, gaps, fit, coded);
        if (!plan || bytes_of(p) < bytes_of(*plan) || (bytes_of(p) == bytes_of(*plan) && planes == plan->planes &&
                                                        p.bits < plan->bits))
          plan = std::move(p);
      }
    return std::move(*plan);
  };
  struct Trial {
    int neighbours = 0;
    TablePlan plan;
    std::vector<Symbol> symbols;
  };
  std::optional<Trial> best;
  const std::size_t depth_rows = 18 * kAlphabet;  // the freq entries of one depth
  // One traversal per neighbour count: it gives the symbols for `gaps` and
  // counts those of every weight in `others`, for every depth. Plans for one
  // weight at all depths, and for each depth's best weight, are compared without symbols; a better ranking is then traversed
  // again for its symbols.
  // The plans of one traversal's symbols (ranked with neighbours, fit and
  // gaps, counted for `others`), kept in `best` when smaller.
  const auto evaluate = [&](Traversal& traversal, int neighbours, int fit, const std::vector<int>& gaps,
                            const std::vector<int>& others) {
    std::vector<std::uint64_t> freq(static_cast<std::size_t>(q) * depth_rows, 0);
    for (const Symbol& s : traversal.symbols)
      ++freq[((static_cast<std::size_t>(s.depth) * 9 + s.weight) * 2 + s.plane) * kAlphabet + s.index];
    TablePlan plan = plan_of(freq, gaps, fit);
    bool better = false;
    for (std::size_t j = 0; j < others.size(); ++j) {
      TablePlan p = plan_of(traversal.counts[j], std::vector<int>(static_cast<std::size_t>(q), others[j]), fit);
      if (bytes_of(p) < bytes_of(plan)) plan = std::move(p), better = true;
    }
    // Each depth's weight: the one whose symbols have the least entropy in
    // that depth's contexts (w, x) (table costs aside; the plan decides),
    // among the gap weights (mix 0), and also with far ranking (mix 1).
    if (!others.empty()) {
      const int mixes = any_far(others) ? 2 : 1;
      std::vector<std::vector<int>> mixed(2, std::vector<int>(static_cast<std::size_t>(q), 0));
      std::vector<std::vector<std::uint64_t>> mixed_freq(2, freq);
      for (int d = 0; d < q; ++d) {
        const std::size_t at = static_cast<std::size_t>(d) * depth_rows;
        const auto cost = [&](const auto& f) {
          double bits = 0;
          std::array<std::uint64_t, kAlphabet> row_counts;
          for (std::size_t row = 0; row < 18; ++row) {
            const auto* counts = row_of(f, static_cast<std::size_t>(d) * 18 + row);
            if (!counts) continue;  // adds the 0 bits of an empty row
            std::copy_n(counts, kAlphabet, row_counts.begin());
            bits += entropy_bits(row_counts.data(), kAlphabet);
          }
          return bits;
        };
        const double plain = cost(freq);
        double least[2] = {plain, plain};
        for (std::size_t j = 0; j < others.size(); ++j) {
          const double c = cost(traversal.counts[j]);
          for (int m = others[j] == kFarRanking ? 1 : 0; m < mixes; ++m) {
            if (!(c < least[m])) continue;
            least[m] = c;
            mixed[static_cast<std::size_t>(m)][static_cast<std::size_t>(d)] = others[j];
            for (std::size_t row = 0; row < 18; ++row) {
              const auto to = mixed_freq[static_cast<std::size_t>(m)].begin() +
                              static_cast<std::ptrdiff_t>(at + row * kAlphabet);
              const std::uint32_t* counts = traversal.counts[j].row(static_cast<std::size_t>(d) * 18 + row);
              if (counts) std::copy_n(counts, kAlphabet, to);
              else std::fill_n(to, kAlphabet, 0);
            }
          }
        }
      }
      for (std::size_t m = 0; m < static_cast<std::size_t>(mixes); ++m) {
        TablePlan p = plan_of(mixed_freq[m], mixed[m], fit);
        if (bytes_of(p) < bytes_of(plan)) plan = std::move(p), better = true;
      }
    }
    if (!best || bytes_of(plan) < bytes_of(best->plan)) {
      // The symbols of the weights chosen: kept by the traversal (the
      // same as ranking again with them).
      if (better && !traversal.rank_with(gaps, plan.gaps)) {
        level.set_neighbours(neighbours, fit);
        level.set_twin(false);
        level.set_gaps(plan.gaps);
        traversal.symbols = Traversal(level, added, q).symbols;
      }
      best = Trial{neighbours, std::move(plan), std::move(traversal.symbols)};
    }
  };
  const auto trial = [&](int neighbours, int fit, const std::vector<int>& gaps, const std::vector<int>& others) {
    level.set_neighbours(neighbours, fit);
    level.set_gaps(gaps, !others.empty());
    Traversal traversal(level, added, q, others);
    evaluate(traversal, neighbours, fit, gaps, others);
  };
  const std::vector<int> none(static_cast<std::size_t>(q), 0);
  if (forced) {
    trial(forced->neighbours, forced->fit, gaps_of(*forced, q), {});
  } else if (fast) {
    // No neighbours: nothing to search for while decoding.
    trial(0, 0, none, {});
  } else {
    // The plane through 4 neighbours suits surfaces; the nearest point alone
    // suits volume interiors. With 4 neighbours (and all coders allowed),
    // the gap weights 1 to 12 and the far ranking are tried too, and then the
    // quadric through 10 neighbours, with the same weights.
    const int neighbours = coarse.size() == 1 ? 1 : 4;
    const std::vector<int> weights{1, 2, 3, 4, 6, 8, 12, kFarRanking};
    std::optional<Traversal> nearest;  // the last trial's symbols, when known from the first traversal
    if (all_coders && coarse.size() >= 6) {
      // The plane's trial, the quadric's and the nearest point's from one
      // traversal: the plane through the first 4 of the quadric's 10
      // neighbours is the plane's own, and the first of them the nearest.
      level.set_neighbours(neighbours, kQuadricNeighbours);
      level.set_gaps(none, true);
      level.set_twin(true);
      Traversal traversal(level, added, q, weights, true);
      level.set_twin(false);
      nearest.emplace(traversal.nearest());
      traversal.swap_twin();
      evaluate(traversal, neighbours, 0, none, weights);
      traversal.swap_twin();
      evaluate(traversal, neighbours, kQuadricNeighbours, none, weights);
    } else {
      trial(neighbours, 0, none, all_coders && neighbours >= 2 ? weights : std::vector<int>{});
    }
    // Where far ranking won (volume interiors: added points sit in the holes
    // between coarse points), the nearest of more neighbours marks the
    // holes better.
    if (all_coders && any_far(best->plan.gaps)) trial(kFarNeighbours, 0, none, weights);
    if (nearest) evaluate(*nearest, 1, 0, none, {});
    else if (neighbours != 1) trial(1, 0, none, {});
  }
  if (forced && forced->paired) {
    pair_tables(best->symbols, best->plan, true);
  } else if (all_coders) {
    // Pairing changes what a table costs: the table layouts of the chosen
    // ranking are planned again, each with its tables paired where smaller.
    std::vector<std::uint64_t> freq(static_cast<std::size_t>(q) * depth_rows, 0);
    for (const Symbol& s : best->symbols)
      ++freq[((static_cast<std::size_t>(s.depth) * 9 + s.weight) * 2 + s.plane) * kAlphabet + s.index];
    TablePlan chosen = best->plan;
    pair_tables(best->symbols, chosen);
    for (int planes : plane_choices)
      for (int classes = 1; classes <= kMaxClasses; ++classes) {
        TablePlan p = plan_tables(freq, q, classes, planes, best->plan.gaps, best->plan.fit, coded);
        pair_tables(best->symbols, p);
        if (bytes_of(p) < bytes_of(chosen)) chosen = std::move(p);
      }
    best->plan = std::move(chosen);
  }
  return {static_cast<std::uint8_t>(coder_of(best->plan)), write_layer(best->symbols, best->plan, best->neighbours)};
}

// ---------------------------------------------------------------- decoder

class Decoder {
 public:
  Decoder(BitReader& in, int q, const std::vector<GridPoint>& coarse, std::uint64_t n_added, TableForm form,
          RefineCoder coder)
      : in_(in), q_(q), n_added_(n_added) {
    neighbours_ = static_cast<int>(in.get(4));
    classes_ = static_cast<int>(in.get(2)) + 1;
    std::vector<int> gaps(static_cast<std::size_t>(q), 0);
    int fit = 0;
    const bool flagged = coder == RefineCoder::ranked_octree;  // the full header
    if (flagged) {
      planes_ = static_cast<int>(in.get(1)) + 1;
      fit = static_cast<int>(in.get(4));
      const bool varies = in.get(1) != 0;
      if (!varies) std::fill(gaps.begin(), gaps.end(), static_cast<int>(in.get(kFarWeightBits)));
      else
        for (int& g : gaps) g = static_cast<int>(in.get(kFarWeightBits));
      for (int g : gaps)
        if (g > kFarRanking)
          fail(Status::bad_layer, std::string(kWhat) + ": ranking weight " + std::to_string(g) + " is not 0-16");
    }
    const int per_depth = classes_ * planes_;
    table_.assign(static_cast<std::size_t>(q * per_depth), -1);
    for (int d = 0; d < q; ++d)
      for (int k = 0; k < classes_; ++k)
        for (int x = 0; x < planes_; ++x) {
          const auto slot = static_cast<std::size_t>((d * classes_ + k) * planes_ + x);
          if (in.get(1)) {
            codes_.push_back(TableCode::read(in, kAlphabet, flagged, slot_name(d, k, x), form));
            table_[slot] = static_cast<int>(codes_.size() - 1);
          } else if (d > 0) {
            table_[slot] = table_[slot - static_cast<std::size_t>(per_depth)];
          }
        }
    level_.emplace(coarse, q);
    level_->set_neighbours(neighbours_, fit);
    level_->set_gaps(gaps);
    visit(0, 0, 0, level_->size(), nullptr);
  }

  std::vector<std::uint64_t> keys;  // the added points, Morton order

 private:
  void visit(int d, std::uint64_t key, std::uint32_t c0, std::uint32_t c1, const CoarseLevel::Candidates* inherited) {
    std::array<std::uint32_t, 9> cb{};
    level_->split(d, key, c0, c1, cb);
    unsigned mask = 0;
    for (std::size_t c = 0; c < 8; ++c)
      if (cb[c + 1] > cb[c]) mask |= 1u << c;
    const int k = std::min(popcount8(mask), classes_ - 1);
    // The ranking first: the plane context depends on the plane it fits.
    CoarseLevel::Candidates fresh;
    std::array<int, 8> order{};
    int split = 0;
    const CoarseLevel::Candidates* handed = level_->rank(d, key, mask, inherited, fresh, order, &split);
    const int x = planes_ == 2 ? plane_context(split) : 0;
    const int t = table_[static_cast<std::size_t>((d * classes_ + k) * planes_ + x)];
    if (t < 0) fail(Status::bad_layer, std::string(kWhat) + ": no code for " + slot_name(d, k, x));
    const unsigned occ = occupancy_of(order, codes_[static_cast<std::size_t>(t)].decode(in_));
    if (d + 1 == q_) {
      if (occ & mask) fail(Status::bad_layer, std::string(kWhat) + ": an added point coincides with a coarse point");
      for (std::uint64_t c = 0; c < 8; ++c)
        if (occ & (1u << c)) {
          if (keys.size() == n_added_)
            fail(Status::bad_layer, std::string(kWhat) + ": more than the declared " + std::to_string(n_added_) +
                                        " points");
          keys.push_back((key << 3) | c);
        }
      return;
    }
    for (std::size_t c = 0; c < 8; ++c)
      if (occ & (1u << c)) visit(d + 1, (key << 3) | c, cb[c], cb[c + 1], handed);
  }

  std::string slot_name(int d, int k, int x) const {
    return std::string(kWhat) + " table for depth " + std::to_string(d) + " class " + std::to_string(k) +
           (planes_ == 2 ? " plane context " + std::to_string(x) : "");
  }

  BitReader& in_;
  int q_;
  std::uint64_t n_added_;
  int planes_ = 1;
  int neighbours_ = 0, classes_ = 1;
  std::vector<TableCode> codes_;
  std::vector<int> table_;  // [(d * classes + k) * planes + x]: index into codes_, -1 for none
  std::optional<CoarseLevel> level_;
};

}  // namespace

std::vector<std::uint8_t> encode_refinement(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                                            int q) {
  return encode_impl(coarse, added, q, nullptr, false).bytes;
}

std::vector<std::uint8_t> encode_refinement(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                                            int q, const RefinementParams& params) {
  return encode_impl(coarse, added, q, &params, false).bytes;
}

RefinementLayer encode_refinement_layer(const std::vector<GridPoint>& coarse, const std::vector<GridPoint>& added,
                                        int q, bool fast) {
  return encode_impl(coarse, added, q, nullptr, true, fast);
}

std::vector<GridPoint> decode_refinement(const std::uint8_t* data, std::size_t size, int q,
                                         const std::vector<GridPoint>& coarse, std::uint64_t n_added, TableForm form,
                                         RefineCoder coder) {
  if (!is_octree_refine_coder(static_cast<std::uint8_t>(coder)))
    fail(Status::invalid_argument, std::string(kWhat) + ": not a conditional octree coder");
  check_coarse(coarse, q);
  if (n_added == 0) {
    if (size != 0) fail(Status::bad_layer, std::string(kWhat) + ": payload present for zero added points");
    return {};
  }
  BitReader in(data, size, kWhat);
  const Decoder decoder(in, q, coarse, n_added, form, coder);
  in.expect_end();
  if (decoder.keys.size() != n_added)
    fail(Status::bad_layer, std::string(kWhat) + ": " + std::to_string(decoder.keys.size()) + " points, " +
                                std::to_string(n_added) + " declared");
  std::vector<GridPoint> points(decoder.keys.size());
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = morton_point(decoder.keys[i], q);
  sort_canonical(points);
  return points;
}

}  // namespace hmc::detail
