// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Template definitions for joint_refinement.hpp.

#include <cmath>

#include "common/ray_circle.hpp"

namespace lidarcal::calibration {

template <typename T>
T KnownRange::distance(const Beam& b, const T& radius) const {
  if (!pole) return T(b.distance_m);
  return rayCircleDistance(T(0), T(0), T(b.angle_rad), T(centre_x_m), T(centre_y_m), radius);
}

}  // namespace lidarcal::calibration
