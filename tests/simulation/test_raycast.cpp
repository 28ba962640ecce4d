// SPDX-License-Identifier: BSD-3-Clause
// Ray casting against closed-form cases.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "simulation/raycast.hpp"

namespace lidarcal::simulation {
namespace {

Ray rayAt(double ox, double oy, double angle) {
  return Ray{ox, oy, std::cos(angle), std::sin(angle)};
}

TEST(RayCircle, CylinderStraightAheadIsHitAtCentreDistanceMinusRadius) {
  const auto t = intersectCircle(rayAt(0, 0, 0), Cylinder{5.0, 0.0, 0.5});
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 4.5, 1e-12);
}

TEST(RayCircle, TangentBeamTouchesAndAnOffsetBeamMisses) {
  const Cylinder c{5.0, 0.5, 0.5};  // touches the x axis at (5, 0)
  const auto t = intersectCircle(rayAt(0, 0, 0), c);
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 5.0, 1e-9);
  EXPECT_FALSE(intersectCircle(rayAt(0, -1e-6, 0), c));
  // Just inside the tangent: the chord is short and the entry is near (5, 0).
  const auto inside = intersectCircle(rayAt(0, 1e-4, 0), c);
  ASSERT_TRUE(inside);
  EXPECT_NEAR(*inside, 5.0 - std::sqrt(0.25 - 0.4999 * 0.4999), 1e-9);
}

TEST(RayCircle, CircleBehindOrAroundTheOriginIsNotHit) {
  EXPECT_FALSE(intersectCircle(rayAt(0, 0, kPi), Cylinder{5.0, 0.0, 0.5}));
  EXPECT_FALSE(intersectCircle(rayAt(5, 0, 0), Cylinder{5.0, 0.0, 0.5}));
}

TEST(RaySegment, WallAtAnAngle) {
  // Wall through (3, 0) at 30 degrees from the y axis; a beam along x hits it at (3, 0).
  const double a = deg2rad(30.0);
  const Segment w{3.0 - 2.0 * std::sin(a), -2.0 * std::cos(a), 3.0 + 2.0 * std::sin(a),
                  2.0 * std::cos(a)};
  const auto t = intersectSegment(rayAt(0, 0, 0), w);
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 3.0, 1e-12);
  Scene scene;
  scene.walls.push_back(w);
  const RayHit hit = castRay(scene, rayAt(0, 0, 0));
  EXPECT_EQ(hit.kind, io::TargetKind::wall);
  EXPECT_NEAR(hit.incidence_rad, a, 1e-12);
  // A beam at angle b hits the wall at distance d/cos(b - a) ... from the wall's normal:
  // perpendicular distance from the origin is 3 cos(a), the normal points along angle -a.
  const double b = deg2rad(10.0);
  const auto tb = intersectSegment(rayAt(0, 0, b), w);
  ASSERT_TRUE(tb);
  EXPECT_NEAR(*tb, 3.0 * std::cos(a) / std::cos(b + a), 1e-12);
}

TEST(RaySegment, MissesBeyondItsEndsAndWhenParallel) {
  const Segment w{3.0, -1.0, 3.0, 1.0};
  EXPECT_FALSE(intersectSegment(rayAt(0, 0, deg2rad(40.0)), w));
  EXPECT_FALSE(intersectSegment(rayAt(0, 0, kPi / 2), w));
  EXPECT_FALSE(intersectSegment(rayAt(0, 0, kPi), w));
}

TEST(CastRay, ReportsTheNearestSurfaceWithItsKindAndId) {
  Scene scene;
  scene.landmarks = {Cylinder{6.0, 0.0, 0.2}, Cylinder{4.0, 0.0, 0.2}};
  scene.clutter = {Cylinder{3.0, 3.0, 0.02}};
  scene.walls = {Segment{8.0, -5.0, 8.0, 5.0}};
  RayHit h = castRay(scene, rayAt(0, 0, 0));
  EXPECT_EQ(h.kind, io::TargetKind::landmark);
  EXPECT_EQ(h.id, 2);
  EXPECT_NEAR(h.range_m, 3.8, 1e-12);
  EXPECT_NEAR(h.incidence_rad, 0.0, 1e-6);
  h = castRay(scene, rayAt(0, 0, kPi / 4));
  EXPECT_EQ(h.kind, io::TargetKind::clutter);
  h = castRay(scene, rayAt(0, 0, deg2rad(20)));
  EXPECT_EQ(h.kind, io::TargetKind::wall);
  EXPECT_NEAR(h.range_m, 8.0 / std::cos(deg2rad(20)), 1e-12);
  EXPECT_EQ(castRay(scene, rayAt(0, 0, kPi)).kind, io::TargetKind::none);
}

TEST(RayCircle, PropertyHitPointLiesOnTheCircleAndNothingIsCloser) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-5.0, 5.0), ang(-kPi, kPi), rad(0.05, 1.0);
  int hits = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    SCOPED_TRACE(trial);
    const Cylinder c{u(rng), u(rng), rad(rng)};
    const Ray ray = rayAt(u(rng), u(rng), ang(rng));
    const auto t = intersectCircle(ray, c);
    if (std::hypot(ray.ox - c.x_m, ray.oy - c.y_m) <= c.radius_m) continue;
    // Distance from the centre to the ray's line, and whether the circle lies ahead.
    const double along = (c.x_m - ray.ox) * ray.dx + (c.y_m - ray.oy) * ray.dy;
    const double perp = std::abs((c.x_m - ray.ox) * ray.dy - (c.y_m - ray.oy) * ray.dx);
    const bool expect_hit = along > 0 && perp < c.radius_m;
    ASSERT_EQ(static_cast<bool>(t), expect_hit);
    if (!t) continue;
    ++hits;
    EXPECT_NEAR(std::hypot(ray.ox + *t * ray.dx - c.x_m, ray.oy + *t * ray.dy - c.y_m), c.radius_m,
                1e-9);
    EXPECT_NEAR(*t, along - std::sqrt(c.radius_m * c.radius_m - perp * perp), 1e-9);
  }
  EXPECT_GT(hits, 50);
}

}  // namespace
}  // namespace lidarcal::simulation
