// SPDX-License-Identifier: AGPL-3.0-or-later
// Distance from a point to a triangle set (encoder side, non-normative):
// an AABB tree over the triangles with exact point-triangle distances at the
// leaves. The encoder uses it to find reconstructed faces that stray from
// the input surface; the fidelity report uses it for Hausdorff distances.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hmc/mesh.hpp"

namespace hmc::detail {

class SurfaceDistance {
 public:
  using Face = std::array<std::uint32_t, 3>;
  /// Both vectors must outlive the object.
  SurfaceDistance(const std::vector<Vec3>& points, const std::vector<Face>& triangles);
  /// Euclidean distance from q to the nearest triangle (infinite if none).
  double operator()(const Vec3& q) const;

 private:
  struct Node {
    Vec3 lo, hi;
    std::uint32_t begin, end, left = 0, right = 0;
  };
  std::uint32_t build(std::uint32_t b, std::uint32_t e);
  void search(std::uint32_t id, const Vec3& q, double& best) const;
  double triangle2(const Face& f, const Vec3& q) const;
  const std::vector<Vec3>& p_;
  const std::vector<Face>& tris_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace hmc::detail
