// SPDX-License-Identifier: AGPL-3.0-or-later
#include "quant/scalar_quantizer.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "util/error.hpp"

namespace hmc {

Vec3 ScalarQuantizer::dequantize(const GridPoint& p) const noexcept {
  // Normative: one rounding for the product, one for the sum (-ffp-contract=off).
  Vec3 v;
  for (int a = 0; a < 3; ++a) {
    const double scaled = static_cast<double>(p[a]) * step;
    v[a] = origin[a] + scaled;
  }
  return v;
}

}  // namespace hmc

namespace hmc::detail {

namespace {

// The checks both quantizers make of their arguments: q in 1..21, points,
// and only finite coordinates.
void check_input(const std::vector<Vec3>& points, int q) {
  if (q < 1 || q > 21) fail(Status::invalid_argument, "bits must be between 1 and 21, got " + std::to_string(q));
  if (points.empty()) fail(Status::invalid_argument, "the input has no points");
  for (std::size_t i = 0; i < points.size(); ++i)
    for (const double v : points[i])
      if (!std::isfinite(v))
        fail(Status::invalid_argument, "point " + std::to_string(i) + " has a " + (std::isnan(v) ? "NaN" : "infinite") +
                                           " coordinate");
}

}  // namespace

ScalarQuantizer fit_quantizer(const std::vector<Vec3>& points, int q) {
  check_input(points, q);
  Vec3 lo = points[0], hi = points[0];
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const double v = points[i][a];
      lo[a] = std::min(lo[a], v);
      hi[a] = std::max(hi[a], v);
    }
  double extent = 0;
  for (int a = 0; a < 3; ++a) {
    const double e = hi[a] - lo[a];
    if (!std::isfinite(e)) fail(Status::invalid_argument, "the coordinate range overflows binary64");
    extent = std::max(extent, e);
  }
  // -0.0 and +0.0 compare equal, so which one min() keeps depends on the
  // input order; take +0.0 so that the stream codes the set, not the order.
  for (double& o : lo)
    if (o == 0) o = 0.0;
  ScalarQuantizer sq;
  sq.bits = q;
  sq.origin = lo;
  sq.step = extent > 0 ? extent / static_cast<double>((std::uint32_t{1} << q) - 1) : 1.0;
  if (!(sq.step > 0) || !std::isfinite(sq.step))
    fail(Status::invalid_argument, "the coordinate range is too small to quantize (step underflows)");
  return sq;
}

ScalarQuantizer lattice_quantizer(const std::vector<Vec3>& points, int q, const Vec3& origin, double step) {
  check_input(points, q);
  for (double o : origin)
    if (!std::isfinite(o)) fail(Status::invalid_argument, "the lattice origin is not finite");
  if (!(step > 0) || !std::isfinite(step)) fail(Status::invalid_argument, "the lattice step must be finite and > 0");
  ScalarQuantizer sq;
  sq.bits = q;
  sq.origin = origin;
  for (double& o : sq.origin)
    if (o == 0) o = 0.0;
  sq.step = step;
  const double top = static_cast<double>(sq.cells() - 1);
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const double v = points[i][a];
      // The same rounding as quantize(): it must land on the grid unclamped.
      const double t = std::round((v - sq.origin[a]) / sq.step);
      if (!(t >= 0 && t <= top))
        fail(Status::invalid_argument, "point " + std::to_string(i) + " lies outside the given lattice (axis " +
                                           std::to_string(a) + ", grid coordinate " + std::to_string(t) + ", q = " +
                                           std::to_string(q) + ")");
    }
  return sq;
}

std::vector<GridPoint> quantize(const std::vector<Vec3>& points, const ScalarQuantizer& sq) {
  const double top = static_cast<double>(sq.cells() - 1);
  std::vector<GridPoint> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      // Round half away from zero (= half up: the offset is never negative).
      const double t = std::round((points[i][a] - sq.origin[a]) / sq.step);
      out[i][a] = static_cast<std::uint32_t>(std::clamp(t, 0.0, top));
    }
  return out;
}

}  // namespace hmc::detail
