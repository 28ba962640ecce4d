// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Where a beam meets a pole: the distance along a ray to a circle. Templated so that Ceres'
// automatic derivatives pass through it.

#include <cmath>

namespace lidarcal {

/// Distance along a ray from (px, py) at angle a to the circle (cx, cy, r); for a ray that
/// misses, the distance to the point of closest approach (continuous at the tangent).
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

}  // namespace lidarcal
