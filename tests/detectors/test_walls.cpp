// SPDX-License-Identifier: BSD-3-Clause
// Walls in a scan (detectors/walls.hpp) and the surfaces of a stop (detectors/wall_tracks.hpp),
// against rooms the test builds: every wall found where it stands, corners split, a wall
// interrupted by a gap merged, a noisy far wall found only with the threshold growing with range.
// Also walls in runs of ordered points (detectors/walls.hpp, findWallsInRun) against their closed
// forms: a straight run is one wall with the line's normal and distance, a corner is split into
// its two walls, a rigid rotation of the scene turns the normals by as much, short runs and bad
// settings give no wall or a clean error; the normal form of the total-least-squares line.

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "common/pose2.hpp"
#include "detectors/wall_tracks.hpp"
#include "detectors/walls.hpp"

namespace lidarcal::detectors {
namespace {

/// A straight wall: the points x cos(normal) + y sin(normal) = distance.
struct TrueWall {
  double normal_rad, distance_m;
};

/// One 360-beam scan (1 degree) from the origin of a convex room bounded by `walls` (each beam
/// reads the nearest wall), range noise `sigma_m`; beams listed in `gap` have no return.
pcl::PointCloud<pcl::PointXYZI> roomScan(const std::vector<TrueWall>& walls, double sigma_m,
                                         std::mt19937_64& rng, const std::vector<int>& gap = {}) {
  std::normal_distribution<double> noise(0.0, 1.0);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  for (int i = 0; i < 360; ++i) {
    const double a = deg2rad(i);
    double range = 1e9;
    for (const TrueWall& w : walls) {
      const double c = std::cos(a - w.normal_rad);
      if (c > 1e-6) range = std::min(range, w.distance_m / c);
    }
    range += sigma_m * noise(rng);
    pcl::PointXYZI p;
    const bool none = std::find(gap.begin(), gap.end(), i) != gap.end();
    p.x = none ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(range * std::cos(a));
    p.y = none ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(range * std::sin(a));
    p.z = 0.0f;
    p.intensity = 0.0f;
    cloud.push_back(p);
  }
  return cloud;
}

/// The found wall whose normal is nearest `normal_rad`.
const Wall* nearest(const std::vector<Wall>& walls, double normal_rad) {
  const Wall* best = nullptr;
  for (const Wall& w : walls)
    if (!best || std::abs(wrapAngle(w.normal_rad - normal_rad)) <
                     std::abs(wrapAngle(best->normal_rad - normal_rad)))
      best = &w;
  return best;
}

// The four walls of a room seen from inside form one cluster (each corner joins two walls):
// split at the corners, each wall is found at its normal and distance.
TEST(FindWalls, EveryWallOfARoomSeenFromInsideIsFoundWhereItStands) {
  const std::vector<TrueWall> room{
      {deg2rad(20), 2.5}, {deg2rad(110), 1.8}, {deg2rad(200), 3.2}, {deg2rad(290), 2.2}};
  std::mt19937_64 rng(1);
  const auto walls = findWalls(roomScan(room, 0.0, rng), WallConfig{});
  ASSERT_EQ(walls.size(), room.size());
  for (const TrueWall& t : room) {
    const Wall* w = nearest(walls, t.normal_rad);
    ASSERT_NE(w, nullptr);
    EXPECT_NEAR(w->normal_rad, wrapAngle(t.normal_rad), 1e-5);
    EXPECT_NEAR(w->distance_m, t.distance_m, 1e-5);
  }
}

// A wall interrupted by beams without return (a table leg, a dark patch) is two clusters of the
// segmentation, and one wall: merged, with the inliers of both pieces.
TEST(FindWalls, PiecesOfOneWallAreMergedIntoOne) {
  const std::vector<TrueWall> room{
      {0.0, 2.0}, {deg2rad(90), 2.0}, {deg2rad(180), 2.0}, {deg2rad(270), 2.0}};
  std::mt19937_64 rng(2);
  // a gap on the wall at 0 deg
  const auto walls = findWalls(roomScan(room, 0.0, rng, {0, 1, 2, 3, 4}), WallConfig{});
  ASSERT_EQ(walls.size(), 4u);
  const Wall* w = nearest(walls, 0.0);
  EXPECT_NEAR(w->distance_m, 2.0, 1e-5);
  // Beams 315..359 and 5..44 meet it before the corners: all of them inliers, on both sides of the
  // gap.
  EXPECT_TRUE(std::find(w->inliers.begin(), w->inliers.end(), 10) != w->inliers.end());
  EXPECT_TRUE(std::find(w->inliers.begin(), w->inliers.end(), 350) != w->inliers.end());
  EXPECT_GE(w->inliers.size(), 80u);
}

// A triangulation lidar's noise grows with range squared: at 3.5 m with 2 cm of noise a fixed
// 1 cm inlier threshold keeps too few of a wall's points (the walls come apart or are missed);
// t(r) = 0.01 + 0.005 r^2 finds each wall whole.
TEST(FindWalls, ANoisyFarWallNeedsTheThresholdThatGrowsWithRange) {
  const std::vector<TrueWall> room{
      {0.0, 3.5}, {deg2rad(90), 3.5}, {deg2rad(180), 3.5}, {deg2rad(270), 3.5}};
  int fixed_whole = 0;
  for (int seed = 0; seed < 10; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    const auto cloud = roomScan(room, 0.02, rng);
    WallConfig growing;
    growing.threshold_per_m2 = 0.005;
    const auto walls = findWalls(cloud, growing);
    ASSERT_EQ(walls.size(), 4u);
    for (const Wall& w : walls) {
      EXPECT_NEAR(w.distance_m, 3.5, 0.01);
      EXPECT_GE(w.inliers.size(), 80u);  // of the 89 beams before the corners
    }
    const auto fixed = findWalls(cloud, WallConfig{});
    fixed_whole += fixed.size() == 4 && std::all_of(fixed.begin(), fixed.end(), [](const Wall& w) {
                     return w.inliers.size() >= 80;
                   });
  }
  EXPECT_LT(fixed_whole, 5);
}

// Sightings of the surfaces of two stops: the scans of a stop see each surface a little
// differently; a cabinet 0.4 m in front of a wall, facing the same way, is another surface.
TEST(LabelWallSurfaces, SightingsOfOneSurfaceShareAnIdAndACabinetInFrontIsAnother) {
  std::vector<WallSighting> walls;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> jitter(0.0, 1.0);
  for (std::size_t stop = 0; stop < 2; ++stop)
    for (std::size_t scan = 0; scan < 10; ++scan)
      for (const TrueWall& t :
           {TrueWall{deg2rad(30), 2.4}, TrueWall{deg2rad(30), 2.8}, TrueWall{deg2rad(-150), 3.1}}) {
        WallSighting w;
        w.stop = stop;
        w.scan = stop * 10 + scan;
        w.normal_rad = t.normal_rad + deg2rad(1.5) * jitter(rng);
        w.distance_m = t.distance_m + 0.005 * jitter(rng);
        w.beams.resize(10 + scan);
        walls.push_back(w);
      }
  std::vector<WallSighting> shuffled = walls;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  labelWallSurfaces(walls);
  labelWallSurfaces(shuffled);
  // Ids by ascending mean normal: the surface at -150 deg is 1, the two at 30 deg are 2 and 3.
  for (const WallSighting& w : walls) {
    if (w.normal_rad < 0.0)
      EXPECT_EQ(w.wall, 1);
    else
      EXPECT_TRUE(w.wall == 2 || w.wall == 3) << w.wall;
  }
  // One id per surface and stop, the same whatever the input order.
  for (std::size_t i = 0; i < walls.size(); ++i)
    for (std::size_t j = 0; j < walls.size(); ++j) {
      if (walls[i].stop != walls[j].stop) continue;
      const bool same_surface = std::abs(walls[i].distance_m - walls[j].distance_m) < 0.1;
      EXPECT_EQ(walls[i].wall == walls[j].wall, same_surface) << i << " " << j;
    }
  for (const WallSighting& w : shuffled) {
    const auto it = std::find_if(walls.begin(), walls.end(), [&](const WallSighting& x) {
      return x.scan == w.scan && x.normal_rad == w.normal_rad && x.distance_m == w.distance_m;
    });
    ASSERT_NE(it, walls.end());
    EXPECT_EQ(it->wall, w.wall);
  }
}

/// n points along the wall x cos(normal) + y sin(normal) = distance, from -half to +half metres
/// along it, seen from the origin in beam order, with Gaussian noise across it.
std::vector<Eigen::Vector2d> wallPoints(double normal_rad, double distance_m, double half_m, int n,
                                        double sigma = 0.0, unsigned seed = 1) {
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
      run.emplace_back(std::cos(turn) * p.x() - std::sin(turn) * p.y(),
                       std::sin(turn) * p.x() + std::cos(turn) * p.y());
    const auto walls = findWallsInRun(run, RunWallConfig{});
    ASSERT_EQ(walls.size(), 2u);
    EXPECT_NEAR(wrapAngle(walls[0].normal_rad - turn), 0.0, 1e-9);
    EXPECT_NEAR(wrapAngle(walls[1].normal_rad - (turn + kPi / 2.0)), 0.0, 1e-9);
    for (const auto& w : walls) EXPECT_NEAR(w.distance_m, 2.0, 1e-9);
    // Every piece within the tolerance of its own line.
    for (const auto& w : walls)
      for (const auto k : w.inliers) {
        const auto& q = run[static_cast<std::size_t>(k)];
        EXPECT_LE(std::abs(q.x() * std::cos(w.normal_rad) + q.y() * std::sin(w.normal_rad) -
                           w.distance_m),
                  0.025);
      }
  }
}

TEST(WallsInRun, ShortRunsGiveNoWallAndBadSettingsAnError) {
  EXPECT_TRUE(findWallsInRun({}, RunWallConfig{}).empty());
  // 7 inner points
  EXPECT_TRUE(findWallsInRun(wallPoints(0.0, 1.0, 0.5, 9), RunWallConfig{}).empty());
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
