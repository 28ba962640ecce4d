// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Template definitions for joint_refinement.hpp.

#include <cmath>

namespace lidarcal::calibration {

template <typename T>
T rayCircleDistance(const T& px, const T& py, const T& a, const T& cx, const T& cy, const T& r) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T c = cos(a), s = sin(a);
  const T dx = cx - px, dy = cy - py;
  const T along = dx * c + dy * s;  // distance to the point of closest approach
  const T perp = dy * c - dx * s;   // miss distance of the ray from the centre
  const T disc = r * r - perp * perp;
  if (disc > T(0)) return along - sqrt(disc);
  return along;
}

template <typename T>
T KnownRange::distance(const Beam& b, const T& radius) const {
  if (!pole) return T(b.distance_m);
  return rayCircleDistance(T(0), T(0), T(b.angle_rad), T(centre_x_m), T(centre_y_m), radius);
}

}  // namespace lidarcal::calibration
