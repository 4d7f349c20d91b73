// SPDX-License-Identifier: AGPL-3.0-or-later
#include "encoder/winding.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <numeric>

#include "delaunay/predicates.hpp"
#include "util/error.hpp"
#include "util/single_faces.hpp"

namespace hmc::detail {

namespace {

constexpr double kPi = 3.14159265358979323846;
// A cluster whose bounding sphere is seen from farther than this many radii
// is replaced by its expansion to second order; the error is then well below
// what the thresholds of the inside test (1/4, 1/2, 3/4) need. On 20,000
// queries at 0.001 to 0.3 diagonals from the Stanford bunny's vertices the
// largest error is 0.027 (mean 0.005), where the dipole alone at 2.5 radii,
// used before, gave 0.057 (0.014) with 1.6 to 2 times the work; at the
// centre of a 2,208-triangle sphere 0.015 either way.
constexpr double kFarRatio = 1.5;
constexpr std::uint32_t kLeafSize = 8;

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

// Nodes of a tree over n items that splits every range of more than `leaf`
// items at its middle (both trees below), so that their node lists are
// allocated once at their final size: growing them by doubling left up to
// half of the horse's 12 MB winding tree unused. The ranges of one depth
// have at most two sizes, s and s + 1.
std::size_t halving_tree_nodes(std::size_t n, std::size_t leaf) {
  std::size_t nodes = 0;
  std::vector<std::pair<std::size_t, std::size_t>> depth{{n, 1}}, next;  // (range size, ranges)
  while (!depth.empty()) {
    next.clear();
    auto add = [&](std::size_t size, std::size_t count) {
      for (auto& [s, c] : next)
        if (s == size) return void(c += count);
      next.push_back({size, count});
    };
    for (const auto& [size, count] : depth) {
      nodes += count;
      if (size > leaf) add(size / 2, count), add(size - size / 2, count);
    }
    depth.swap(next);
  }
  return nodes;
}

// Van Oosterom & Strackee: the solid angle of triangle abc seen from q is
// 2·arg(den + i·det), with det and den below.
struct HalfAngle {
  double det, den;
};
HalfAngle half_angle(const std::array<Vec3, 3>& t, const Vec3& q) {
  const Vec3 a = sub(t[0], q), b = sub(t[1], q), c = sub(t[2], q);
  const double la = norm(a), lb = norm(b), lc = norm(c);
  return {dot(a, cross(b, c)), la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb};
}

// Sum of the half solid angles of several triangles with one atan2: the
// argument of the product of the complex numbers den + i·det, counting the
// turns the running product makes past -1. A factor with det = 0 (q in the
// triangle's plane) is added on its own, as atan2 gives it (0 or ±π).
class HalfAngleSum {
 public:
  void add(const HalfAngle& h) {
    if (h.det == 0) {
      flat_ += std::atan2(h.det, h.den);
      return;
    }
    const double nr = re_ * h.den - im_ * h.det, ni = re_ * h.det + im_ * h.den;
    // The product's argument is in (-π, π]; adding one in (0, π) to a
    // positive one passes π when the new imaginary part is negative, adding
    // one in (-π, 0) to a negative one passes -π when it is not.
    const bool positive = im_ > 0 || (im_ == 0 && re_ < 0);
    if (positive && h.det > 0 && ni < 0) ++turns_;
    if (im_ < 0 && h.det < 0 && ni >= 0) --turns_;
    re_ = nr;
    im_ = ni;
    // Only the argument matters: rescale before the magnitude could leave
    // the range of doubles.
    const double size = std::max(std::fabs(nr), std::fabs(ni));
    if (size > 1e100 || (size < 1e-100 && size > 0)) re_ /= size, im_ /= size;
  }
  double value() const { return std::atan2(im_, re_) + 2 * kPi * turns_ + flat_; }

 private:
  double re_ = 1, im_ = 0, flat_ = 0;
  int turns_ = 0;
};

}  // namespace

WindingNumber::WindingNumber(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles)
    : points_(points), tri_(triangles) {
  order_.resize(tri_.size());
  for (std::uint32_t i = 0; i < order_.size(); ++i) order_[i] = i;
  nodes_.reserve(1 + (tri_.empty() ? 0 : halving_tree_nodes(tri_.size(), kLeafSize)));
  nodes_.push_back({});  // index 0 is never a child, so left == 0 marks a leaf
  Moments root;
  if (!tri_.empty()) build(0, static_cast<std::uint32_t>(tri_.size()), root);
  // The triangles in tree order, so that a leaf's lie side by side.
  std::vector<Triangle> in_order(tri_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) in_order[i] = tri_[order_[i]];
  tri_.swap(in_order);
  std::vector<std::uint32_t>().swap(order_);
}

std::uint32_t WindingNumber::build(std::uint32_t begin, std::uint32_t end, Moments& mo) {
  const auto id = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back({});
  Node n;
  n.begin = begin;
  n.end = end;
  double total = 0;
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::uint32_t i = begin; i < end; ++i) {
    const auto t = corners(order_[i]);
    const Vec3 av = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    const double w = 0.5 * norm(av);
    for (int a = 0; a < 3; ++a) {
      n.area[a] += 0.5 * av[a];
      n.centre[a] += w * (t[0][a] + t[1][a] + t[2][a]) / 3;
      for (const auto& v : t) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
    }
    total += w;
  }
  for (int a = 0; a < 3; ++a) n.centre[a] = total > 0 ? n.centre[a] / total : 0.5 * (lo[a] + hi[a]);
  double r2 = 0;  // the radius, squared until the end (the same largest root)
  for (std::uint32_t i = begin; i < end; ++i)
    for (const auto& v : corners(order_[i])) {
      const Vec3 d = sub(v, n.centre);
      r2 = std::max(r2, dot(d, d));
    }
  n.radius = std::sqrt(r2);
  // Triangle t, area vector a_t, contributes a_t · g(x) integrated over its
  // area (per unit area), g(x) = (x - q) / |x - q|^3. Around the centre p,
  // with e = x - p: g(x) = g(p) + J e + (1/2) H[e, e] + ..., so the cluster
  // needs M = sum a_t ⊗ E[e] (first order) and T = sum a_t ⊗ E[e ⊗ e]
  // (second order), E the mean over the triangle: E[e] = c - p and
  // E[e ⊗ e] = (c - p) ⊗ (c - p) + (1/12) sum over the vertices v of
  // (v - c) ⊗ (v - c), c the centroid. A leaf sums them over its
  // triangles; a parent moves its children's to its own centre (with
  // δ = p_child - p: M += A ⊗ δ, T_ajk += M_aj δ_k + M_ak δ_j + A_a δ_j δ_k,
  // A the child's area vector), each triangle once instead of once per
  // level of the tree.
  if (end - begin > kLeafSize) {
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    const std::uint32_t mid = begin + (end - begin) / 2;
    auto key = [&](std::uint32_t i) {
      const auto& t = tri_[i];
      return points_[t[0]][axis] + points_[t[1]][axis] + points_[t[2]][axis];
    };
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](std::uint32_t x, std::uint32_t y) { return key(x) < key(y); });
    Moments child[2];
    n.left = build(begin, mid, child[0]);
    n.right = build(mid, end, child[1]);
    mo = Moments{};
    for (int c = 0; c < 2; ++c) {
      const Node& k = nodes_[c == 0 ? n.left : n.right];
      const Vec3 d = sub(k.centre, n.centre);
      const Moments& x = child[c];
      for (int a = 0; a < 3; ++a)
        for (int j = 0; j < 3; ++j) {
          mo.m[a][j] += x.m[a][j] + k.area[a] * d[j];
          for (int l = 0; l < 3; ++l)
            mo.t[a][j][l] += x.t[a][j][l] + x.m[a][j] * d[l] + x.m[a][l] * d[j] + k.area[a] * d[j] * d[l];
        }
    }
  } else {
    mo = Moments{};
    for (std::uint32_t i = begin; i < end; ++i) {
      const auto t = corners(order_[i]);
      const Vec3 av = cross(sub(t[1], t[0]), sub(t[2], t[0]));
      Vec3 c, e;
      for (int a = 0; a < 3; ++a) c[a] = (t[0][a] + t[1][a] + t[2][a]) / 3, e[a] = c[a] - n.centre[a];
      double s2[3][3];
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) {
          double own = 0;
          for (const auto& v : t) own += (v[j] - c[j]) * (v[k] - c[k]);
          s2[j][k] = e[j] * e[k] + own / 12;
        }
      for (int a = 0; a < 3; ++a) {
        const double half = 0.5 * av[a];
        for (int j = 0; j < 3; ++j) {
          mo.m[a][j] += half * e[j];
          for (int k = 0; k < 3; ++k) mo.t[a][j][k] += half * s2[j][k];
        }
      }
    }
  }
  const auto& m = mo.m;
  const auto& t3 = mo.t;
  // With r = p - q: J = I / r^3 - 3 r r^T / r^5 and H_ijk = -3 (δ_ij r_k +
  // δ_ik r_j + δ_jk r_i) / r^5 + 15 r_i r_j r_k / r^7, contracted with M and
  // T (which is symmetric in its last two indices) in query().
  n.trace1 = m[0][0] + m[1][1] + m[2][2];
  n.quad1 = {m[0][0], m[1][1], m[2][2], m[0][1] + m[1][0], m[0][2] + m[2][0], m[1][2] + m[2][1]};
  for (int a = 0; a < 3; ++a)
    for (int j = 0; j < 3; ++j) {
      n.u2[a] += t3[j][j][a];  // sum_j T_jja (= T_jaj)
      n.v2[a] += t3[a][j][j];  // sum_j T_ajj
    }
  // The cubic form sum_ijk T_ijk r_i r_j r_k by monomial: xxx, yyy, zzz,
  // xxy, xxz, yyx, yyz, zzx, zzy, xyz.
  auto sym = [&](int i, int j, int k) {  // sum of T over the distinct orders of (i, j, k)
    if (i == j && j == k) return t3[i][i][i];
    if (i == j) return t3[i][i][k] + t3[i][k][i] + t3[k][i][i];
    return t3[i][j][k] + t3[i][k][j] + t3[j][i][k] + t3[j][k][i] + t3[k][i][j] + t3[k][j][i];
  };
  n.cubic2 = {sym(0, 0, 0), sym(1, 1, 1), sym(2, 2, 2), sym(0, 0, 1), sym(0, 0, 2),
              sym(1, 1, 0), sym(1, 1, 2), sym(2, 2, 0), sym(2, 2, 1), sym(0, 1, 2)};
  nodes_[id] = n;
  return id;
}

double WindingNumber::query(std::uint32_t id, const Vec3& q) const {
  const Node& n = nodes_[id];
  const Vec3 d = sub(n.centre, q);
  const double d2 = dot(d, d), far = kFarRatio * n.radius;
  if (d2 > far * far && d2 > 0) {
    const double r3 = d2 * std::sqrt(d2), r5 = r3 * d2, r7 = r5 * d2;
    const double x = d[0], y = d[1], z = d[2];
    const auto& q1 = n.quad1;
    const auto& c2 = n.cubic2;
    const double quad = q1[0] * x * x + q1[1] * y * y + q1[2] * z * z + q1[3] * x * y + q1[4] * x * z + q1[5] * y * z;
    const double cubic = c2[0] * x * x * x + c2[1] * y * y * y + c2[2] * z * z * z + c2[3] * x * x * y +
                         c2[4] * x * x * z + c2[5] * y * y * x + c2[6] * y * y * z + c2[7] * z * z * x +
                         c2[8] * z * z * y + c2[9] * x * y * z;
    const double first = (n.trace1 - 3 * quad / d2) / r3;
    const double second = 0.5 * (15 * cubic / r7 - 3 * (2 * dot(n.u2, d) + dot(n.v2, d)) / r5);
    return dot(n.area, d) / r3 + first + second;
  }
  if (n.left == 0) {
    HalfAngleSum s;
    for (std::uint32_t i = n.begin; i < n.end; ++i) s.add(half_angle(corners(i), q));
    return 2 * s.value();
  }
  return query(n.left, q) + query(n.right, q);
}

double WindingNumber::operator()(const Vec3& q) const {
  if (tri_.empty()) return 0;
  return query(1, q) / (4 * kPi);
}

namespace {

constexpr std::uint32_t kBoxLeaf = 4;
constexpr double kQuarterLimit = 4194304.0;  // 2^22 grid units

// det [u; v; w] for entries below 2^26 in magnitude: the minors stay below
// 2^53, the result below 2^81.
Int128 det(const ClosedSurface::Point& u, const ClosedSurface::Point& v, const ClosedSurface::Point& w) {
  return det3({u[0], u[1], u[2]}, {v[0], v[1], v[2]}, {w[0], w[1], w[2]});
}

// A point of grid units on the quarter grid (exact: multiples of 1/4 below 2^22).
std::array<std::int32_t, 3> quarter(const Vec3& p) {
  return {static_cast<std::int32_t>(4 * p[0]), static_cast<std::int32_t>(4 * p[1]), static_cast<std::int32_t>(4 * p[2])};
}

ClosedSurface::Point minus(const ClosedSurface::Point& a, const std::array<std::int32_t, 3>& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

}  // namespace

bool ClosedSurface::exact(const std::vector<Vec3>& points) {
  for (const auto& p : points)
    for (double c : p)
      if (!(c >= 0 && c < kQuarterLimit) || c != std::floor(c)) return false;
  return true;
}

ClosedSurface::ClosedSurface(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles,
                             const std::array<std::uint32_t, 6>* box) {
  // The border: each undirected edge's net use, +1 for every use from its
  // smaller vertex to its larger one, -1 for the other direction.
  std::vector<std::pair<std::uint64_t, int>> uses;
  uses.reserve(3 * triangles.size());
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = t[k], b = t[(k + 1) % 3];
      if (a != b) uses.push_back({a < b ? a << 32 | b : b << 32 | a, a < b ? 1 : -1});
    }
  std::sort(uses.begin(), uses.end());
  std::vector<std::array<std::uint32_t, 2>> border;  // directed tail -> head, repeated by net use
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    int net = 0;
    while (j < uses.size() && uses[j].first == uses[i].first) net += uses[j++].second;
    const auto lo = static_cast<std::uint32_t>(uses[i].first >> 32), hi = static_cast<std::uint32_t>(uses[i].first);
    for (int m = 0; m < std::abs(net); ++m) border.push_back(net > 0 ? std::array{lo, hi} : std::array{hi, lo});
    i = j;
  }
  // Caps, per connected part of the border: a fan (apex, head, tail) for a
  // cut around the box, the part's closed walks halved for any other.
  if (!border.empty()) {
    std::vector<std::uint32_t> verts;
    for (const auto& e : border) verts.insert(verts.end(), e.begin(), e.end());
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    auto local = [&](std::uint32_t v) {
      return static_cast<std::uint32_t>(std::lower_bound(verts.begin(), verts.end(), v) - verts.begin());
    };
    std::vector<std::uint32_t> parent(verts.size());
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](std::uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (const auto& e : border) parent[find(local(e[0]))] = find(local(e[1]));
    for (std::uint32_t v : verts) cap_points_.push_back(points[v]);
    std::vector<std::uint32_t> apex(verts.size(), ~0u);
    std::vector<std::array<double, 4>> sum(verts.size(), {0, 0, 0, 0});
    for (std::uint32_t i = 0; i < verts.size(); ++i) {
      auto& s = sum[find(i)];
      for (int a = 0; a < 3; ++a) s[a] += points[verts[i]][a];
      s[3] += 1;
    }
    // With a box: per part, its longest edge per axis, then the faces of
    // the box (bit 2a: below face a's low side, 2a+1: above its high side)
    // each vertex lies beyond by more than that, the faces all its
    // vertices share one of (`cut`, one side per axis at most), and the
    // part's extreme coordinates.
    std::vector<double> reach(box ? verts.size() : 0, 0);
    std::vector<std::uint8_t> side(box ? verts.size() : 0, 0);
    std::vector<std::array<double, 6>> extreme(box ? verts.size() : 0);
    std::vector<std::int8_t> cut(box ? verts.size() : 0, -1);  // the chosen faces' bits; -1: none fits
    if (box) {
      for (const auto& e : border) {
        double& r = reach[find(local(e[0]))];
        for (int a = 0; a < 3; ++a) r = std::max(r, std::abs(points[e[0]][a] - points[e[1]][a]));
      }
      for (std::uint32_t i = 0; i < verts.size(); ++i) extreme[i] = {1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
      for (std::uint32_t i = 0; i < verts.size(); ++i) {
        const Vec3& p = points[verts[i]];
        const std::uint32_t r = find(i);
        for (int a = 0; a < 3; ++a) {
          if (p[a] + reach[r] < (*box)[a]) side[i] |= std::uint8_t(1u << (2 * a));
          if (p[a] - reach[r] >= (*box)[3 + a]) side[i] |= std::uint8_t(2u << (2 * a));
          extreme[r][a] = std::min(extreme[r][a], p[a]);
          extreme[r][3 + a] = std::max(extreme[r][3 + a], p[a]);
        }
      }
      // Candidate face sets, fewest faces first: a set fits a part if every
      // vertex of it lies beyond one of its faces.
      std::vector<std::uint8_t> sets;
      for (int faces = 1; faces <= 3; ++faces)
        for (int code = 0; code < 27; ++code) {
          std::uint8_t set = 0;
          int n = 0;
          for (int a = 0, c = code; a < 3; ++a, c /= 3)
            if (c % 3) set |= std::uint8_t((c % 3) << (2 * a)), ++n;
          if (n == faces) sets.push_back(set);
        }
      std::vector<std::uint32_t> members(verts.size());
      std::iota(members.begin(), members.end(), 0u);
      std::sort(members.begin(), members.end(), [&](std::uint32_t x, std::uint32_t y) { return find(x) < find(y); });
      for (std::size_t b = 0; b < members.size();) {
        std::size_t e = b;
        const std::uint32_t r = find(members[b]);
        while (e < members.size() && find(members[e]) == r) ++e;
        for (const std::uint8_t set : sets) {
          bool fits = true;
          for (std::size_t k = b; k < e && fits; ++k) fits = (side[members[k]] & set) != 0;
          if (fits) {
            cut[r] = static_cast<std::int8_t>(set);
            break;
          }
        }
        b = e;
      }
    }
    // A cut's cap: a fan from its apex beyond the box.
    for (std::uint32_t i = 0; i < verts.size(); ++i)
      if (find(i) == i && box && cut[i] >= 0) {
        apex[i] = static_cast<std::uint32_t>(cap_points_.size());
        Vec3 c;  // beyond the cut's faces: its extreme coordinates there, the mean (on the quarter grid) elsewhere
        for (int a = 0; a < 3; ++a) {
          const int bits = (cut[i] >> (2 * a)) & 3;
          c[a] = bits == 1 ? extreme[i][a] : bits == 2 ? extreme[i][3 + a] : std::round(4 * sum[i][a] / sum[i][3]) / 4;
        }
        cap_points_.push_back(c);
      }
    for (const auto& e : border) {
      const std::uint32_t r = find(local(e[0]));
      if (apex[r] == ~0u) continue;
      caps_.push_back({apex[r], local(e[1]), local(e[0])});
      cap_outside_.push_back(1);
    }
    // Any other part: its border edges as closed walks (every vertex is
    // entered as often as left, so a walk can only stop where it began),
    // each closed by halving: the triangle of its first vertex and those a
    // third and two thirds along it, then on each arc the triangle of its
    // ends and its middle vertex, and so on. Its triangles are then as
    // small as the arcs they span, where a fan from one apex made every
    // triangle reach across the whole part, so that the caps' winding
    // number (subtracted at every tetrahedron) could not use its far-field
    // expansion: a 5,557-edge cut of a 20M-point model's tile (625,002
    // points, 3.9M tetrahedra) took over 15 minutes there.
    std::vector<std::uint32_t> first_out(verts.size() + 1, 0), out(border.size());
    for (const auto& e : border) ++first_out[local(e[0]) + 1];
    for (std::size_t i = 0; i < verts.size(); ++i) first_out[i + 1] += first_out[i];
    std::vector<std::uint32_t> next_out(first_out.begin(), first_out.end() - 1);
    for (std::uint32_t k = 0; k < border.size(); ++k) out[next_out[local(border[k][0])]++] = k;
    next_out.assign(first_out.begin(), first_out.end() - 1);
    std::vector<std::uint8_t> used(border.size(), 0);
    std::vector<std::uint32_t> walk;
    std::vector<std::array<std::uint32_t, 2>> arcs;
    for (std::uint32_t k = 0; k < border.size(); ++k) {
      if (used[k] || apex[find(local(border[k][0]))] != ~0u) continue;
      const std::uint32_t start = local(border[k][0]);
      walk.assign(1, start);
      used[k] = 1;
      for (std::uint32_t at = local(border[k][1]); at != start;) {
        while (next_out[at] < first_out[at + 1] && used[out[next_out[at]]]) ++next_out[at];
        if (next_out[at] == first_out[at + 1]) fail(Status::internal_error, "a border walk is stuck");
        const std::uint32_t e = out[next_out[at]++];
        used[e] = 1;
        walk.push_back(at);
        at = local(border[e][1]);
      }
      const auto m = static_cast<std::uint32_t>(walk.size());
      if (m < 3) continue;  // there and back: no border
      auto vertex = [&](std::uint32_t x) { return walk[x % m]; };
      // (last, middle, first): the walk's own direction reversed, as the fan's.
      caps_.push_back({vertex(2 * m / 3), vertex(m / 3), vertex(0)});
      cap_outside_.push_back(0);
      arcs.assign({{0, m / 3}, {m / 3, 2 * m / 3}, {2 * m / 3, m}});
      while (!arcs.empty()) {
        const auto [from, to] = arcs.back();
        arcs.pop_back();
        if (to - from < 2) continue;
        const std::uint32_t mid = from + (to - from) / 2;
        caps_.push_back({vertex(to), vertex(mid), vertex(from)});
        cap_outside_.push_back(0);
        arcs.push_back({from, mid});
        arcs.push_back({mid, to});
      }
    }
  }
  auto add = [&](const std::array<std::int32_t, 3>& a, const std::array<std::int32_t, 3>& b,
                 const std::array<std::int32_t, 3>& c) {
    const Point u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const std::array<std::int64_t, 3> n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    // A triangle of no area adds nothing to the winding number, and a
    // segment through it changes nothing.
    if (n[0] != 0 || n[1] != 0 || n[2] != 0) tris_.push_back({a, b, c, n});
  };
  tris_.reserve(triangles.size() + caps_.size());
  for (const auto& t : triangles) add(quarter(points[t[0]]), quarter(points[t[1]]), quarter(points[t[2]]));
  for (const auto& t : caps_) add(quarter(cap_points_[t[0]]), quarter(cap_points_[t[1]]), quarter(cap_points_[t[2]]));
  boxes_.reserve(1 + (tris_.empty() ? 0 : halving_tree_nodes(tris_.size(), kBoxLeaf)));
  boxes_.push_back({});  // index 0 is never a child
  if (!tris_.empty()) build(0, static_cast<std::uint32_t>(tris_.size()));
}

ClosedSurface::Box ClosedSurface::bounds(const Tri& t) {
  Box b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = std::min({t.a[a], t.b[a], t.c[a]});
    b.hi[a] = std::max({t.a[a], t.b[a], t.c[a]});
  }
  return b;
}

std::uint32_t ClosedSurface::build(std::uint32_t begin, std::uint32_t end) {
  const auto id = static_cast<std::uint32_t>(boxes_.size());
  boxes_.push_back({});
  Box box = bounds(tris_[begin]);
  for (std::uint32_t i = begin + 1; i < end; ++i) {
    const Box b = bounds(tris_[i]);
    for (int a = 0; a < 3; ++a) box.lo[a] = std::min(box.lo[a], b.lo[a]), box.hi[a] = std::max(box.hi[a], b.hi[a]);
  }
  box.begin = begin;
  box.end = end;
  if (end - begin > kBoxLeaf) {
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (box.hi[a] - box.lo[a] > box.hi[axis] - box.lo[axis]) axis = a;
    const std::uint32_t mid = begin + (end - begin) / 2;
    auto key = [axis](const Tri& t) { return std::int64_t{t.a[axis]} + t.b[axis] + t.c[axis]; };
    std::nth_element(tris_.begin() + begin, tris_.begin() + mid, tris_.begin() + end,
                     [&](const Tri& x, const Tri& y) { return key(x) < key(y); });
    box.left = build(begin, mid);
    box.right = build(mid, end);
  }
  boxes_[id] = box;
  return id;
}

std::optional<int> ClosedSurface::jump(const Point& p, const Point& q) const {
  if (tris_.empty()) return 0;
  Point lo, hi;
  for (int a = 0; a < 3; ++a) lo[a] = std::min(p[a], q[a]), hi[a] = std::max(p[a], q[a]);
  const Point u{q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  // The segment p + s·u, 0 <= s <= 1, meets a box only if the parameter
  // intervals of its three slabs overlap there (in floating point, on the
  // box grown by one unit: a cull, which the exact test below does not rely
  // on; a long segment's bounding box holds many boxes it misses).
  double inv[3];
  for (int a = 0; a < 3; ++a) inv[a] = u[a] != 0 ? 1.0 / static_cast<double>(u[a]) : 0.0;
  auto meets = [&](const Box& b) {
    double s0 = 0, s1 = 1;
    for (int a = 0; a < 3; ++a) {
      if (u[a] == 0) continue;  // within the slab: the bounding-box test
      double e0 = (static_cast<double>(b.lo[a] - 1) - static_cast<double>(p[a])) * inv[a];
      double e1 = (static_cast<double>(b.hi[a] + 1) - static_cast<double>(p[a])) * inv[a];
      if (e0 > e1) std::swap(e0, e1);
      s0 = std::max(s0, e0);
      s1 = std::min(s1, e1);
    }
    return s0 <= s1;
  };
  // Only a segment long against the surface's extent passes the bounding
  // boxes of many boxes it misses; for the short ones (from a centroid to
  // the next) the slab test rejected under 2 % of the boxes that their
  // bounding box meets (horse, 4 levels), and cost more than it saved.
  const Box& root = boxes_[1];
  bool slab = false;
  for (int a = 0; a < 3; ++a) slab = slab || (hi[a] - lo[a]) * 16 > std::int64_t{root.hi[a]} - root.lo[a];
  // The bounding-box test of a box, its three axes at once: (lo, hi[0]) and
  // (hi, begin) as four lanes each; the fourth lanes compare against the
  // extremes and never fail. Box corners are int32 and not negative, so the
  // segment's bounds clamped to int32 give the same answers.
  typedef std::int32_t Lanes __attribute__((vector_size(16)));
  static_assert(offsetof(Box, hi) == offsetof(Box, lo) + 12 && sizeof(Box) >= offsetof(Box, hi) + 16,
                "a box's lo and hi are loaded as four lanes each");
  auto narrow = [](std::int64_t x) {
    return static_cast<std::int32_t>(std::clamp<std::int64_t>(x, INT32_MIN, INT32_MAX));
  };
  const Lanes seg_hi{narrow(hi[0]), narrow(hi[1]), narrow(hi[2]), INT32_MAX};
  const Lanes seg_lo{narrow(lo[0]), narrow(lo[1]), narrow(lo[2]), INT32_MIN};
  auto apart = [&](const Box& b) {
    const char* bytes = reinterpret_cast<const char*>(&b);  // the box's own bytes
    Lanes l, h;
    std::memcpy(&l, bytes + offsetof(Box, lo), sizeof l);
    std::memcpy(&h, bytes + offsetof(Box, hi), sizeof h);
    const Lanes out = (l > seg_hi) | (h < seg_lo);
    return (out[0] | out[1] | out[2]) != 0;
  };
  int total = 0;
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 1;
  while (top > 0) {
    const Box& b = boxes_[stack[--top]];
    if (apart(b)) continue;
    if (slab && !meets(b)) continue;
    if (b.left != 0) {
      stack[top++] = b.left;
      stack[top++] = b.right;
      continue;
    }
    for (std::uint32_t i = b.begin; i < b.end; ++i) {
      const Tri& t = tris_[i];
      const Point pa = minus(p, t.a), qa = minus(q, t.a);
      const Int128 sp = Int128{t.n[0]} * pa[0] + Int128{t.n[1]} * pa[1] + Int128{t.n[2]} * pa[2];
      const Int128 sq = Int128{t.n[0]} * qa[0] + Int128{t.n[1]} * qa[1] + Int128{t.n[2]} * qa[2];
      if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0)) continue;  // both ends on one side
      // The segment reaches the plane: does its line pass inside the
      // triangle? The three edges' signed volumes with it agree there.
      const Point ap{t.a[0] - p[0], t.a[1] - p[1], t.a[2] - p[2]}, bp{t.b[0] - p[0], t.b[1] - p[1], t.b[2] - p[2]},
          cp{t.c[0] - p[0], t.c[1] - p[1], t.c[2] - p[2]};
      const int e1 = sign_of(det(u, ap, bp)), e2 = sign_of(det(u, bp, cp)), e3 = sign_of(det(u, cp, ap));
      if ((e1 > 0 || e2 > 0 || e3 > 0) && (e1 < 0 || e2 < 0 || e3 < 0)) continue;  // the line misses it
      if (e1 == 0 || e2 == 0 || e3 == 0 || sp == 0 || sq == 0) return std::nullopt;
      total += sp > 0 ? 1 : -1;  // from the normal's side (outside) in: one more
    }
  }
  return total;
}

ClosedSurface::Point ClosedSurface::outside(int which) const {
  const Box& root = boxes_.size() > 1 ? boxes_[1] : Box{};
  return {std::int64_t{root.lo[0]} - 1 - which, std::int64_t{root.lo[1]} - 3 - 5 * which,
          std::int64_t{root.lo[2]} - 7 - 11 * which};
}

double winding_number(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles, const Vec3& q) {
  HalfAngleSum s;
  for (const auto& t : triangles) s.add(half_angle({points[t[0]], points[t[1]], points[t[2]]}, q));
  return 2 * s.value() / (4 * kPi);
}

void orient_positive(const std::vector<Vec3>& points, Tetrahedron& t) {
  const Vec3 u = sub(points[t[1]], points[t[0]]), v = sub(points[t[2]], points[t[0]]),
             w = sub(points[t[3]], points[t[0]]);
  if (!(dot(u, cross(v, w)) > 0)) std::swap(t[2], t[3]);
}

std::vector<Triangle> boundary_faces(const std::vector<Vec3>& points, const std::vector<Tetrahedron>& tets) {
  std::vector<Tetrahedron> positive(tets);
  for (auto& t : positive) orient_positive(points, t);
  return boundary_faces(positive);
}

std::vector<Triangle> boundary_faces(const std::vector<Tetrahedron>& positive) {
  // Faces opposite each vertex, counter-clockwise from outside.
  static constexpr int fv[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  if (positive.size() >= (std::size_t{1} << 30)) fail(Status::invalid_argument, "boundary faces: too many tetrahedra");
  return single_faces(4 * positive.size(), [&positive](std::size_t i) {
    const auto& t = positive[i / 4];
    const auto& f = fv[i % 4];
    return Triangle{t[f[0]], t[f[1]], t[f[2]]};
  });
}

}  // namespace hmc::detail
