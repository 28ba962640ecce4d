// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Closed-form ray casting in the scan plane against circles (vertical cylinders) and segments.

#include <optional>

#include "common/scene.hpp"
#include "io/true_ranges.hpp"

namespace lidarcal::simulation {

/// A ray from (ox, oy) along the unit direction (dx, dy).
struct Ray {
  double ox = 0.0, oy = 0.0;  ///< origin, metres
  double dx = 1.0, dy = 0.0;  ///< unit direction
};

/// Where a ray first meets a surface.
struct RayHit {
  double range_m = 0.0;                        ///< distance along the ray, metres
  io::TargetKind kind = io::TargetKind::none;  ///< what was hit (none: nothing)
  int id = 0;                                  ///< 1-based index within its kind
  double incidence_rad = 0.0;  ///< angle between the ray and the surface normal, [0, pi/2]
};

/// Smallest t > 0 with |o + t d - c| = r, the entry point of the ray into the circle.
/// A ray starting inside the circle reports no hit (the sensor cannot be inside a pole).
std::optional<double> intersectCircle(const Ray& ray, const Cylinder& circle);
/// Smallest t > 0 where the ray crosses the segment; parallel rays report no hit.
std::optional<double> intersectSegment(const Ray& ray, const Segment& segment);

/// First surface of the scene on the ray (landmarks, clutter, walls).
RayHit castRay(const Scene& scene, const Ray& ray);

/// Range offset of the surface a ray hit (Cylinder/Segment::range_offset_m; 0 for no hit).
double surfaceOffset(const Scene& scene, const RayHit& hit);
/// Return intensity of the surface hit (0: none recorded, or nothing hit).
double surfaceIntensity(const Scene& scene, const RayHit& hit);

}  // namespace lidarcal::simulation
