// SPDX-License-Identifier: AGPL-3.0-or-later
// A self-contained incremental (Bowyer–Watson) construction of the canonical
// tetrahedralization, using only the exact predicates of predicates.hpp.
//
// It is the backend for inputs on which TetGen cannot be run safely (see
// tetgen_backend.cpp: coordinate extents of 2^16 and more) and a second,
// independent implementation of spec/delaunay.md that the tests compare
// with TetGen. It is written from the spec alone, shares no code with
// TetGen, and could be relicensed permissively.
//
// Representation: cells of four vertex indices and four neighbours, the
// neighbour k being across the face opposite vertex k. Cells with the
// vertex kInf (the point at infinity, always in position 3) are the hull
// cells: (a, b, c, inf) stands for the hull face (a, b, c), oriented so that
// orient3d(a, b, c, x) > 0 for points x beyond it. Finite cells are
// positively oriented.
//
// Conflict of a new point p: a finite cell conflicts iff p is inside its
// perturbed sphere (insphere_perturbed > 0); a hull cell (a, b, c, inf) iff
// orient3d(a, b, c, p) > 0, or = 0 and its finite neighbour conflicts (the
// rule restricted to the hull plane, spec §3.4). The conflict region is
// connected and star-shaped from p; it is replaced by the cone from p over
// its boundary.
#include <algorithm>
#include <cstdint>
#include <random>
#include <string>

#include "delaunay/delaunay.hpp"
#include "delaunay/predicates.hpp"
#include "util/error.hpp"
#include "util/morton.hpp"

namespace hmc::detail::backend {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFu;

// 32 bytes, aligned so that a cell never straddles two cache lines: the
// construction reads cells in no particular order, and unaligned cells made
// a tetrahedralization from scratch 15-18 % slower (bunny, horse: 0.215 ->
// 0.178 s, 0.30 -> 0.26 s, medians of 7 in one process).
struct alignas(32) Cell {
  std::array<std::uint32_t, 4> v;
  std::array<std::uint32_t, 4> n;
};

class Builder {
 public:
  Builder(const std::vector<GridPoint>& pts, std::uint64_t max_cells)
      : p_(pts), inf_(static_cast<std::uint32_t>(pts.size())), max_cells_(max_cells) {}

  void run(std::vector<std::array<std::uint32_t, 4>>& tets, std::vector<std::array<std::uint32_t, 4>>& nb) {
    reserve(0, p_.size());
    std::vector<std::uint32_t> all(p_.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
    auto order = insertion_order(std::move(all));
    start(order);
    for (std::uint32_t i : order) insert(i);
    output(tets, nb);
  }

  // Starts from the tetrahedralization of a subset (its tetrahedra and
  // adjacency, vertices renumbered by `index` into p_) and inserts the other
  // points. The perturbation depends only on the canonical order, which the
  // subset keeps, so the result is the same as building from scratch.
  // The subset's lists are released once copied in.
  void refine(const std::vector<std::uint32_t>& index, std::vector<std::array<std::uint32_t, 4>>& sub_tets,
              std::vector<std::array<std::uint32_t, 4>>& sub_nb, std::vector<std::array<std::uint32_t, 4>>& tets,
              std::vector<std::array<std::uint32_t, 4>>& nb) {
    reserve(sub_tets.size(), p_.size() - std::min(p_.size(), index.size()));
    seed(index, sub_tets, sub_nb);
    std::vector<std::array<std::uint32_t, 4>>().swap(sub_tets);
    std::vector<std::array<std::uint32_t, 4>>().swap(sub_nb);
    std::vector<char> seeded(p_.size(), 0);
    for (std::uint32_t i : index) seeded[i] = 1;
    std::vector<std::uint32_t> rest;
    rest.reserve(p_.size() - index.size());
    for (std::size_t i = 0; i < p_.size(); ++i)
      if (!seeded[i]) rest.push_back(static_cast<std::uint32_t>(i));
    for (std::uint32_t i : insertion_order(std::move(rest))) insert(i);
    output(tets, nb);
  }

 private:
  const std::vector<GridPoint>& p_;
  const std::uint32_t inf_;
  const std::uint64_t max_cells_;  // most cells (finite and hull) alive at once
  std::vector<Cell> cells_;
  std::vector<std::uint32_t> free_;
  std::vector<std::uint32_t> mark_;  // per cell: stamp_ = in conflict, stamp_ + 1 = tested, not in conflict
  std::uint32_t stamp_ = 1;
  std::uint32_t last_ = 0;
  std::array<std::uint32_t, 4> initial_{};
  // Work lists of one insertion.
  std::vector<std::uint32_t> cavity_, stack_;
  struct Boundary {
    std::uint32_t cell;  // cavity cell
    int face;            // its face on the cavity boundary
  };
  std::vector<Boundary> boundary_;
  // The hull edges of a seeded tetrahedralization (seed()).
  struct EdgeSlot {
    std::uint64_t key;
    std::uint32_t cell;
    int face;
  };
  std::vector<EdgeSlot> edges_;
  struct PairSlot {
    std::uint64_t key = 0;
    std::uint32_t stamp = 0, cell = 0;
    int face = 0;
  };
  static constexpr std::uint32_t kPaired = ~std::uint32_t{0};
  std::vector<PairSlot> pair_table_;  // begin_pairs(), pair_face()
  std::uint64_t pair_mask_ = 0;
  std::uint32_t pair_stamp_ = 0;

  bool is_hull(std::uint32_t c) const { return cells_[c].v[3] == inf_; }

  // Room for the cells of `cells` tetrahedra and `points` more points
  // (about 6.5 tetrahedra per point, plus hull cells), within the limit: the
  // cell lists then grow without being copied, and pages they never use
  // are never touched.
  void reserve(std::size_t cells, std::size_t points) {
    const std::uint64_t want = std::min<std::uint64_t>(max_cells_, cells + cells / 8 + 8 * std::uint64_t{points} + 64);
    cells_.reserve(static_cast<std::size_t>(want));
    mark_.reserve(static_cast<std::size_t>(want));
  }

  // BRIO order: a fixed-seed shuffle, then rounds of geometrically growing
  // size, each sorted along a Morton curve.
  std::vector<std::uint32_t> insertion_order(std::vector<std::uint32_t> order) const {
    std::mt19937_64 rng(0x484d43u);
    for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
    std::size_t hi = order.size();
    while (hi > 0) {
      const std::size_t lo = hi > 64 ? hi / 8 : 0;
      std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
      keyed.reserve(hi - lo);
      for (std::size_t i = lo; i < hi; ++i) keyed.push_back({morton_key(p_[order[i]], 21), order[i]});
      std::sort(keyed.begin(), keyed.end());
      for (std::size_t i = lo; i < hi; ++i) order[i] = keyed[i - lo].second;
      hi = lo;
    }
    return order;
  }

  std::uint32_t new_cell(const std::array<std::uint32_t, 4>& v) {
    std::uint32_t c;
    if (!free_.empty()) {
      c = free_.back();
      free_.pop_back();
    } else {
      if (cells_.size() >= max_cells_)
        fail(Status::limit_exceeded, "delaunay: the tetrahedralization of " + std::to_string(p_.size()) +
                                         " points needs more than " + std::to_string(max_cells_) +
                                         " cells, over the memory limit");
      c = static_cast<std::uint32_t>(cells_.size());
      cells_.push_back({});
      mark_.push_back(0);
    }
    cells_[c] = {v, {kNone, kNone, kNone, kNone}};
    mark_[c] = 0;
    return c;
  }

  // Takes four non-coplanar points out of the order (the first two and the
  // next ones that span a triangle and a tetrahedron with them) and builds
  // the first tetrahedron and its four hull cells.
  void start(std::vector<std::uint32_t>& order) {
    const std::size_t n = order.size();
    std::size_t pick[4] = {0, 1, 0, 0};
    const IVec3 u = sub(p_[order[1]], p_[order[0]]);
    std::size_t i = 2;
    for (; i < n; ++i) {
      const IVec3 v = sub(p_[order[i]], p_[order[0]]);
      if (u.y * v.z - u.z * v.y != 0 || u.z * v.x - u.x * v.z != 0 || u.x * v.y - u.y * v.x != 0) break;
    }
    if (i == n) fail(Status::internal_error, "delaunay: collinear input");
    pick[2] = i;
    std::size_t j = 2;
    for (; j < n; ++j)
      if (j != i && orient3d(p_[order[0]], p_[order[1]], p_[order[i]], p_[order[j]]) != 0) break;
    if (j == n) fail(Status::internal_error, "delaunay: coplanar input");
    pick[3] = j;
    std::array<std::uint32_t, 4> t{order[pick[0]], order[pick[1]], order[pick[2]], order[pick[3]]};
    // Move the picked points out of the insertion sequence.
    std::vector<std::uint32_t> rest;
    rest.reserve(n - 4);
    for (std::size_t k = 0; k < n; ++k)
      if (k != pick[0] && k != pick[1] && k != pick[2] && k != pick[3]) rest.push_back(order[k]);
    order = std::move(rest);
    if (orient3d(p_[t[0]], p_[t[1]], p_[t[2]], p_[t[3]]) < 0) std::swap(t[2], t[3]);
    initial_ = t;
    const std::uint32_t c0 = new_cell(t);
    // Hull cell across face k: the face opposite t[k], turned outward
    // (kFaceVertices lists faces outward), then inf.
    for (int k = 0; k < 4; ++k) {
      const int* f = kFaceVertices[k];
      const std::uint32_t h = new_cell({t[f[0]], t[f[1]], t[f[2]], inf_});
      cells_[c0].n[k] = h;
      cells_[h].n[3] = c0;
    }
    // Hull cells meet along the six edges of the first tetrahedron.
    for (std::uint32_t a = 1; a <= 4; ++a)
      for (std::uint32_t b = 1; b <= 4; ++b)
        if (a != b) link_hull_pair(a, b);
    last_ = c0;
  }

  // Cells of a finished tetrahedralization: finite cell t is tetrahedron t
  // (positively oriented, neighbour k across the face opposite vertex k),
  // then one hull cell per hull face, linked along the hull edges.
  void seed(const std::vector<std::uint32_t>& index, const std::vector<std::array<std::uint32_t, 4>>& sub_tets,
            const std::vector<std::array<std::uint32_t, 4>>& sub_nb) {
    if (sub_tets.empty() || sub_nb.size() != sub_tets.size())
      fail(Status::internal_error, "delaunay: nothing to refine");
    for (const auto& t : sub_tets) {
      std::array<std::uint32_t, 4> v{};
      for (int k = 0; k < 4; ++k) {
        if (t[k] >= index.size()) fail(Status::internal_error, "delaunay: seed vertex out of range");
        v[k] = index[t[k]];
      }
      new_cell(v);
    }
    const auto finite = static_cast<std::uint32_t>(sub_tets.size());
    edges_.clear();
    for (std::uint32_t t = 0; t < finite; ++t)
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t u = sub_nb[t][k];
        if (u != kNoTet) {
          if (u >= finite) fail(Status::internal_error, "delaunay: seed neighbour out of range");
          cells_[t].n[k] = u;
          continue;
        }
        const int* f = kFaceVertices[k];
        const std::array<std::uint32_t, 4> v = cells_[t].v;  // a copy: new_cell may move the cells
        const std::uint32_t h = new_cell({v[f[0]], v[f[1]], v[f[2]], inf_});
        cells_[t].n[k] = h;
        cells_[h].n[3] = t;
        // Hull cell h meets another along each hull edge: its face opposite
        // finite vertex i holds inf and the other two.
        for (int i = 0; i < 3; ++i) {
          const std::uint32_t x = cells_[h].v[(i + 1) % 3], y = cells_[h].v[(i + 2) % 3];
          const std::uint64_t key = (static_cast<std::uint64_t>(std::min(x, y)) << 32) | std::max(x, y);
          edges_.push_back({key, h, i});
        }
      }
    std::sort(edges_.begin(), edges_.end(), [](const EdgeSlot& a, const EdgeSlot& b) { return a.key < b.key; });
    if (edges_.size() % 2 != 0) fail(Status::internal_error, "delaunay: seed hull not closed");
    for (std::size_t i = 0; i + 1 < edges_.size(); i += 2) {
      if (edges_[i].key != edges_[i + 1].key || (i + 2 < edges_.size() && edges_[i + 2].key == edges_[i].key))
        fail(Status::internal_error, "delaunay: seed hull not closed");
      cells_[edges_[i].cell].n[edges_[i].face] = edges_[i + 1].cell;
      cells_[edges_[i + 1].cell].n[edges_[i + 1].face] = edges_[i].cell;
    }
    last_ = 0;
  }

  // Links the new cells around p: each edge of the cavity's boundary is
  // shared by exactly two of the new cells' faces through p, which become
  // neighbours. The faces are paired as the cells are made, in a small
  // open-addressing table keyed by the edge (a cavity has a few dozen; a
  // sort of them was 6 % of a decode).
  void begin_pairs(std::size_t faces) {
    if (faces % 2 != 0) fail(Status::internal_error, "delaunay: cavity not a ball");
    std::size_t size = 64;
    while (size < 2 * faces) size *= 2;
    if (pair_table_.size() < size) pair_table_.assign(size, PairSlot{});
    pair_mask_ = size - 1;
    if (++pair_stamp_ == 0) {  // the stamps wrapped: clear the table
      std::fill(pair_table_.begin(), pair_table_.end(), PairSlot{});
      pair_stamp_ = 1;
    }
  }

  // Face `face` of new cell `cell`, through p, whose edge other than p is
  // `key`: linked to the face met before with the same edge, or kept for
  // the one to come. Returns 1 when it was linked.
  int pair_face(std::uint64_t key, std::uint32_t cell, int face) {
    for (std::uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> 32;; ++h) {
      PairSlot& slot = pair_table_[h & pair_mask_];
      if (slot.stamp != pair_stamp_) {  // empty: the first of the pair
        slot = {key, pair_stamp_, cell, face};
        return 0;
      }
      if (slot.key != key) continue;
      if (slot.cell == kPaired) fail(Status::internal_error, "delaunay: cavity not a ball");
      cells_[slot.cell].n[slot.face] = cell;
      cells_[cell].n[face] = slot.cell;
      slot.cell = kPaired;
      return 1;
    }
  }

  // Links hull cells a and b if they share an edge (two finite vertices).
  void link_hull_pair(std::uint32_t a, std::uint32_t b) {
    for (int i = 0; i < 3; ++i) {
      // Face of a opposite its vertex i contains inf and the other two.
      const std::uint32_t x = cells_[a].v[(i + 1) % 3], y = cells_[a].v[(i + 2) % 3];
      const auto& bv = cells_[b].v;
      const bool has_x = bv[0] == x || bv[1] == x || bv[2] == x;
      const bool has_y = bv[0] == y || bv[1] == y || bv[2] == y;
      if (has_x && has_y) cells_[a].n[i] = b;
    }
  }

  // Orientation of cell c with its vertex k replaced by p (finite c).
  int orient_replaced(std::uint32_t c, int k, std::uint32_t p) const {
    std::array<std::uint32_t, 4> v = cells_[c].v;
    v[k] = p;
    return orient3d(p_[v[0]], p_[v[1]], p_[v[2]], p_[v[3]]);
  }

  bool conflicts(std::uint32_t c, std::uint32_t p) {
    if (mark_[c] == stamp_) return true;
    if (mark_[c] == stamp_ + 1) return false;
    bool in;
    const auto& v = cells_[c].v;
    if (v[3] != inf_) {
      in = insphere_perturbed(p_, {v[0], v[1], v[2], v[3], p}) > 0;
    } else {
      const int o = orient3d(p_[v[0]], p_[v[1]], p_[v[2]], p_[p]);
      if (o != 0) {
        in = o > 0;
      } else {
        const std::uint32_t f = cells_[c].n[3];
        const auto& w = cells_[f].v;
        in = insphere_perturbed(p_, {w[0], w[1], w[2], w[3], p}) > 0;
      }
    }
    mark_[c] = in ? stamp_ : stamp_ + 1;
    return in;
  }

  std::uint32_t locate(std::uint32_t p) {
    std::uint32_t c = last_;
    if (is_hull(c)) c = cells_[c].n[3];
    for (std::size_t steps = 0;; ++steps) {
      if (steps > 8 * cells_.size() + 64) fail(Status::internal_error, "delaunay: point location does not end");
      int k = 0;
      for (; k < 4; ++k)
        if (orient_replaced(c, k, p) < 0) break;
      if (k == 4) return c;  // p in the closed tetrahedron: it conflicts
      c = cells_[c].n[k];
      if (is_hull(c)) return c;  // strictly beyond a hull face: conflicts
    }
  }

  void insert(std::uint32_t p) {
    stamp_ += 2;
    if (stamp_ < 2) {  // wrapped: reset the marks
      std::fill(mark_.begin(), mark_.end(), 0);
      stamp_ = 2;
    }
    const std::uint32_t c0 = locate(p);
    mark_[c0] = stamp_;
    cavity_.assign(1, c0);
    stack_.assign(1, c0);
    boundary_.clear();
    while (!stack_.empty()) {
      const std::uint32_t c = stack_.back();
      stack_.pop_back();
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t d = cells_[c].n[k];
        if (mark_[d] == stamp_) continue;
        if (conflicts(d, p)) {
          cavity_.push_back(d);
          stack_.push_back(d);
        } else {
          boundary_.push_back({c, k});
        }
      }
    }
    // Cone from p over the boundary: cell c with its vertex k replaced by p.
    const std::size_t faces = 3 * boundary_.size();
    begin_pairs(faces);
    std::size_t matched = 0;
    for (const auto& b : boundary_) {
      auto v = cells_[b.cell].v;
      v[b.face] = p;
      const std::uint32_t outside = cells_[b.cell].n[b.face];
      // A hull cell keeps inf in position 3 unless its finite face (k = 3)
      // is the boundary face, which makes the new cell finite.
      const std::uint32_t nc = new_cell(v);
      mark_[nc] = 0;
      int pf = 0;  // the new cell's face opposite p
      while (cells_[nc].v[pf] != p) ++pf;
      cells_[nc].n[pf] = outside;
      auto& on = cells_[outside].n;
      for (int k = 0; k < 4; ++k)
        if (on[k] == b.cell) on[k] = nc;
      // The three faces through p, keyed by the edge they share with the
      // boundary face (the two vertices other than p and the opposite one).
      for (int k = 0; k < 4; ++k) {
        if (k == pf) continue;
        std::uint32_t e[2];
        int m = 0;
        for (int j = 0; j < 4; ++j)
          if (j != k && j != pf) e[m++] = cells_[nc].v[j];
        const std::uint64_t key = (static_cast<std::uint64_t>(std::min(e[0], e[1])) << 32) | std::max(e[0], e[1]);
        matched += static_cast<std::size_t>(pair_face(key, nc, k));
      }
      last_ = nc;
    }
    if (2 * matched != faces) fail(Status::internal_error, "delaunay: cavity not a ball");
    for (std::uint32_t c : cavity_) {
      cells_[c].v = {kNone, kNone, kNone, kNone};
      free_.push_back(c);
    }
  }

  void output(std::vector<std::array<std::uint32_t, 4>>& tets, std::vector<std::array<std::uint32_t, 4>>& nb) {
    std::vector<std::uint32_t> id(cells_.size(), kNoTet);
    std::uint32_t count = 0;
    for (std::size_t c = 0; c < cells_.size(); ++c)
      if (cells_[c].v[0] != kNone && cells_[c].v[3] != inf_) id[c] = count++;
    tets.resize(count);
    nb.resize(count);
    for (std::size_t c = 0; c < cells_.size(); ++c) {
      if (id[c] == kNoTet) continue;
      tets[id[c]] = cells_[c].v;
      for (int k = 0; k < 4; ++k) nb[id[c]][k] = id[cells_[c].n[k]];
    }
  }
};

}  // namespace

void native(const std::vector<GridPoint>& points, std::vector<std::array<std::uint32_t, 4>>& tets,
            std::vector<std::array<std::uint32_t, 4>>& neighbors, std::uint64_t max_cells) {
  Builder(points, max_cells).run(tets, neighbors);
}

void native_refine(const std::vector<GridPoint>& points, const std::vector<std::uint32_t>& index,
                   std::vector<std::array<std::uint32_t, 4>>& sub_tets, std::vector<std::array<std::uint32_t, 4>>& sub_neighbors,
                   std::vector<std::array<std::uint32_t, 4>>& tets, std::vector<std::array<std::uint32_t, 4>>& neighbors,
                   std::uint64_t max_cells) {
  Builder(points, max_cells).refine(index, sub_tets, sub_neighbors, tets, neighbors);
}

}  // namespace hmc::detail::backend
