// SPDX-License-Identifier: AGPL-3.0-or-later
#include "encoder/distance.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace hmc::detail {

namespace {

Vec3 sub(const Vec3& x, const Vec3& y) { return {x[0] - y[0], x[1] - y[1], x[2] - y[2]}; }
double dot(const Vec3& x, const Vec3& y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; }

}  // namespace

SurfaceDistance::SurfaceDistance(const std::vector<Vec3>& points, const std::vector<Face>& triangles)
    : p_(points), tris_(triangles), order_(triangles.size()) {
  std::iota(order_.begin(), order_.end(), 0u);
  nodes_.reserve(triangles.size() / 2 + 2);
  if (!triangles.empty()) build(0, static_cast<std::uint32_t>(triangles.size()));
}

double SurfaceDistance::operator()(const Vec3& q) const {
  double best = HUGE_VAL;
  if (!nodes_.empty()) search(0, q, best);
  return std::sqrt(best);
}

std::uint32_t SurfaceDistance::build(std::uint32_t b, std::uint32_t e) {
  const auto id = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back({});
  Node n{{HUGE_VAL, HUGE_VAL, HUGE_VAL}, {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, b, e};
  for (std::uint32_t i = b; i < e; ++i)
    for (auto v : tris_[order_[i]])
      for (int a = 0; a < 3; ++a) n.lo[a] = std::min(n.lo[a], p_[v][a]), n.hi[a] = std::max(n.hi[a], p_[v][a]);
  if (e - b > 4) {
    int ax = 0;
    for (int a = 1; a < 3; ++a)
      if (n.hi[a] - n.lo[a] > n.hi[ax] - n.lo[ax]) ax = a;
    const std::uint32_t m = b + (e - b) / 2;
    auto key = [&](std::uint32_t t) { return p_[tris_[t][0]][ax] + p_[tris_[t][1]][ax] + p_[tris_[t][2]][ax]; };
    std::nth_element(order_.begin() + b, order_.begin() + m, order_.begin() + e,
                     [&](std::uint32_t x, std::uint32_t y) { return key(x) < key(y); });
    n.left = build(b, m);
    n.right = build(m, e);
  }
  nodes_[id] = n;
  return id;
}

void SurfaceDistance::search(std::uint32_t id, const Vec3& q, double& best) const {
  auto box2 = [&](const Node& n) {
    double s = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = std::max({n.lo[a] - q[a], 0.0, q[a] - n.hi[a]});
      s += d * d;
    }
    return s;
  };
  const Node& n = nodes_[id];
  if (box2(n) >= best) return;
  if (n.left == 0 && n.right == 0) {
    for (std::uint32_t i = n.begin; i < n.end; ++i) best = std::min(best, triangle2(tris_[order_[i]], q));
    return;
  }
  const bool left_first = box2(nodes_[n.left]) < box2(nodes_[n.right]);
  search(left_first ? n.left : n.right, q, best);
  search(left_first ? n.right : n.left, q, best);
}

// Squared distance to a triangle by Voronoi regions of its features.
double SurfaceDistance::triangle2(const Face& f, const Vec3& q) const {
  const Vec3 &a = p_[f[0]], &b = p_[f[1]], &c = p_[f[2]];
  const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(q, a);
  auto at = [&](double s, double t) {
    const Vec3 x{a[0] + s * ab[0] + t * ac[0], a[1] + s * ab[1] + t * ac[1], a[2] + s * ab[2] + t * ac[2]};
    const Vec3 d = sub(q, x);
    return dot(d, d);
  };
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return at(0, 0);
  const Vec3 bp = sub(q, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return at(1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(d1 / (d1 - d3), 0);
  const Vec3 cp = sub(q, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return at(0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(0, d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return at(1 - w, w);
  }
  const double den = 1 / (va + vb + vc);
  return at(vb * den, vc * den);
}

}  // namespace hmc::detail
