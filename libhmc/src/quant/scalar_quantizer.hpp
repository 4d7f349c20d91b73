// SPDX-License-Identifier: AGPL-3.0-or-later
// Choosing the uniform scalar quantizer for an input and applying it
// (encoder side; the decoder only dequantizes, see ScalarQuantizer).
#pragma once

#include <vector>

#include "hmc/codec.hpp"
#include "hmc/mesh.hpp"

namespace hmc::detail {

/// The quantizer that maps the bounding box of `points` onto a 2^q grid
/// with one step for all axes: origin = box minimum, step = largest
/// extent / (2^q - 1) (1.0 when all points coincide). Raises
/// invalid_argument on NaN/infinite coordinates or an unrepresentable range.
ScalarQuantizer fit_quantizer(const std::vector<Vec3>& points, int q);

/// The quantizer of a given lattice (EncodeOptions::lattice): raises
/// invalid_argument on a bad lattice, NaN/infinite coordinates, or a point
/// that rounds outside [0, 2^q - 1] on some axis.
ScalarQuantizer lattice_quantizer(const std::vector<Vec3>& points, int q, const Vec3& origin, double step);

/// Grid point of each input point (same order, duplicates kept).
std::vector<GridPoint> quantize(const std::vector<Vec3>& points, const ScalarQuantizer& sq);

}  // namespace hmc::detail
