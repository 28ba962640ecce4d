// Walls in runs of ordered points (detectors/walls.hpp, findWallsInRun) against their closed
// forms: a straight run is one wall with the line's normal and distance, a corner is split into
// its two walls, a rigid rotation of the scene turns the normals by as much, short runs and bad
// settings give no wall or a clean error; the normal form of the total-least-squares line.

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "common/pose2.hpp"
#include "detectors/walls.hpp"

namespace lidarcal::detectors {
namespace {

/// n points along the wall x cos(normal) + y sin(normal) = distance, from -half to +half metres
/// along it, seen from the origin in beam order, with Gaussian noise across it.
std::vector<Eigen::Vector2d> wallPoints(double normal_rad, double distance_m, double half_m, int n, double sigma = 0.0,
                                        unsigned seed = 1) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Eigen::Vector2d nrm(std::cos(normal_rad), std::sin(normal_rad)), along(-nrm.y(), nrm.x());
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i < n; ++i) {
    const double t = -half_m + 2.0 * half_m * i / (n - 1);
    pts.push_back(distance_m * nrm + t * along + (sigma > 0.0 ? sigma * noise(rng) : 0.0) * nrm);
  }
  return pts;
}

TEST(WallsInRun, AStraightRunIsOneWallWithItsNormalAndDistance) {
  for (const double normal : {0.3, 2.0, -1.2, kPi}) {
    SCOPED_TRACE(normal);
    const auto run = wallPoints(normal, 2.5, 1.0, 40, 0.002);
    const auto walls = findWallsInRun(run, RunWallConfig{});
    ASSERT_EQ(walls.size(), 1u);
    EXPECT_NEAR(wrapAngle(walls[0].normal_rad - normal), 0.0, 0.01);
    EXPECT_NEAR(walls[0].distance_m, 2.5, 0.003);
    EXPECT_NEAR(walls[0].rms_m, 0.002, 0.001);
    // The run's two end points are left out; the inliers are the rest, ascending.
    ASSERT_EQ(walls[0].inliers.size(), 38u);
    EXPECT_EQ(walls[0].inliers.front(), 1);
    EXPECT_EQ(walls[0].inliers.back(), 38);
  }
}

TEST(WallsInRun, ACornerIsSplitIntoItsTwoWallsAndARotationTurnsThem) {
  // Two walls meeting at (2, 2): x = 2 for y in [0, 2], then y = 2 for x in [2, 0].
  std::vector<Eigen::Vector2d> corner;
  for (int i = 0; i <= 40; ++i) corner.emplace_back(2.0, 0.05 * i);
  for (int i = 1; i <= 40; ++i) corner.emplace_back(2.0 - 0.05 * i, 2.0);
  for (const double turn : {0.0, 0.7, -2.1}) {
    SCOPED_TRACE(turn);
    std::vector<Eigen::Vector2d> run;
    for (const auto& p : corner)
      run.emplace_back(std::cos(turn) * p.x() - std::sin(turn) * p.y(), std::sin(turn) * p.x() + std::cos(turn) * p.y());
    const auto walls = findWallsInRun(run, RunWallConfig{});
    ASSERT_EQ(walls.size(), 2u);
    EXPECT_NEAR(wrapAngle(walls[0].normal_rad - turn), 0.0, 1e-9);
    EXPECT_NEAR(wrapAngle(walls[1].normal_rad - (turn + kPi / 2.0)), 0.0, 1e-9);
    for (const auto& w : walls) EXPECT_NEAR(w.distance_m, 2.0, 1e-9);
    // Every piece within the tolerance of its own line.
    for (const auto& w : walls)
      for (const auto k : w.inliers) {
        const auto& q = run[static_cast<std::size_t>(k)];
        EXPECT_LE(std::abs(q.x() * std::cos(w.normal_rad) + q.y() * std::sin(w.normal_rad) - w.distance_m), 0.025);
      }
  }
}

TEST(WallsInRun, ShortRunsGiveNoWallAndBadSettingsAnError) {
  EXPECT_TRUE(findWallsInRun({}, RunWallConfig{}).empty());
  EXPECT_TRUE(findWallsInRun(wallPoints(0.0, 1.0, 0.5, 9), RunWallConfig{}).empty());  // 7 inner points
  RunWallConfig keep_ends;
  keep_ends.drop_run_ends = false;
  EXPECT_EQ(findWallsInRun(wallPoints(0.0, 1.0, 0.5, 9), keep_ends).size(), 1u);
  RunWallConfig bad;
  bad.max_deviation_m = 0.0;
  EXPECT_THROW(findWallsInRun(wallPoints(0.0, 1.0, 0.5, 20), bad), std::invalid_argument);
  bad = RunWallConfig{};
  bad.min_points = 1;
  EXPECT_THROW(findWallsInRun(wallPoints(0.0, 1.0, 0.5, 20), bad), std::invalid_argument);
}

TEST(LineNormalForm, PointsAwayFromTheOriginWithANonNegativeDistance) {
  for (const double normal : {0.0, 1.0, 2.5, -2.5}) {
    SCOPED_TRACE(normal);
    const NormalForm nf = normalForm(totalLeastSquaresLine(wallPoints(normal, 1.7, 2.0, 11)));
    EXPECT_NEAR(wrapAngle(nf.normal_rad - normal), 0.0, 1e-12);
    EXPECT_NEAR(nf.distance_m, 1.7, 1e-12);
  }
}

}  // namespace
}  // namespace lidarcal::detectors
