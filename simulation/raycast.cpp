// SPDX-License-Identifier: BSD-3-Clause
#include "simulation/raycast.hpp"

#include <cmath>
#include <limits>

namespace lidarcal::simulation {

std::optional<double> intersectCircle(const Ray& ray, const Cylinder& c) {
  // |o - c + t d|^2 = r^2 with |d| = 1:  t^2 + 2 b t + q = 0.
  const double mx = ray.ox - c.x_m, my = ray.oy - c.y_m;
  const double b = mx * ray.dx + my * ray.dy;
  const double q = mx * mx + my * my - c.radius_m * c.radius_m;
  if (q <= 0.0) return std::nullopt;  // origin inside or on the circle
  const double disc = b * b - q;
  if (disc < 0.0) return std::nullopt;
  // Entry root; written to avoid cancellation: t = q / (-b + sqrt(disc)) = -b - sqrt(disc).
  const double s = std::sqrt(disc);
  // circle behind the origin (q > 0 means both roots share b's sign)
  if (b >= 0.0) return std::nullopt;
  const double t = q / (-b + s);
  return t > 0.0 ? std::optional<double>(t) : std::nullopt;
}

std::optional<double> intersectSegment(const Ray& ray, const Segment& w) {
  const double ex = w.x1_m - w.x0_m, ey = w.y1_m - w.y0_m;
  const double denom = ray.dx * ey - ray.dy * ex;  // cross(d, e)
  if (std::abs(denom) < 1e-15) return std::nullopt;
  const double px = w.x0_m - ray.ox, py = w.y0_m - ray.oy;
  const double t = (px * ey - py * ex) / denom;          // along the ray
  const double u = (px * ray.dy - py * ray.dx) / denom;  // along the segment, [0, 1]
  if (t <= 0.0 || u < 0.0 || u > 1.0) return std::nullopt;
  return t;
}

RayHit castRay(const Scene& scene, const Ray& ray) {
  RayHit best;
  best.range_m = std::numeric_limits<double>::infinity();
  double nx = 0.0, ny = 0.0;  // outward normal at the best hit
  auto circles = [&](const std::vector<Cylinder>& cs, io::TargetKind kind) {
    for (std::size_t i = 0; i < cs.size(); ++i) {
      const auto t = intersectCircle(ray, cs[i]);
      if (t && *t < best.range_m) {
        best = RayHit{*t, kind, static_cast<int>(i) + 1, 0.0};
        nx = (ray.ox + *t * ray.dx - cs[i].x_m) / cs[i].radius_m;
        ny = (ray.oy + *t * ray.dy - cs[i].y_m) / cs[i].radius_m;
      }
    }
  };
  circles(scene.landmarks, io::TargetKind::landmark);
  circles(scene.clutter, io::TargetKind::clutter);
  for (std::size_t i = 0; i < scene.walls.size(); ++i) {
    const auto t = intersectSegment(ray, scene.walls[i]);
    if (t && *t < best.range_m) {
      best = RayHit{*t, io::TargetKind::wall, static_cast<int>(i) + 1, 0.0};
      const auto& w = scene.walls[i];
      const double len = std::hypot(w.x1_m - w.x0_m, w.y1_m - w.y0_m);
      nx = -(w.y1_m - w.y0_m) / len;
      ny = (w.x1_m - w.x0_m) / len;
    }
  }
  if (best.kind == io::TargetKind::none) return RayHit{};
  const double cos_inc = std::min(1.0, std::abs(nx * ray.dx + ny * ray.dy));
  best.incidence_rad = std::acos(cos_inc);
  return best;
}

namespace {

/// `field` of the surface hit (a cylinder or a segment); 0 when nothing was hit.
template <class Field>
double ofSurfaceHit(const Scene& scene, const RayHit& hit, Field field) {
  const auto index = static_cast<std::size_t>(hit.id - 1);
  switch (hit.kind) {
    case io::TargetKind::landmark:
      return field(scene.landmarks.at(index));
    case io::TargetKind::clutter:
      return field(scene.clutter.at(index));
    case io::TargetKind::wall:
      return field(scene.walls.at(index));
    default:
      return 0.0;
  }
}

}  // namespace

double surfaceOffset(const Scene& scene, const RayHit& hit) {
  return ofSurfaceHit(scene, hit, [](const auto& s) { return s.range_offset_m; });
}

double surfaceIntensity(const Scene& scene, const RayHit& hit) {
  return ofSurfaceHit(scene, hit, [](const auto& s) { return s.intensity; });
}

}  // namespace lidarcal::simulation
