// SPDX-License-Identifier: BSD-3-Clause
// FastSLAM (Sharma 2020 ch. 3.1-3.2) on simulated observations with known truth.

#include <cmath>

#include <gtest/gtest.h>

#include "noise/fastslam.hpp"
#include "noise/noise_scenes.hpp"
#include "noise/problem.hpp"
#include "simulation/observation_sim.hpp"

namespace lidarcal::noise {
namespace {

TEST(FastSlam, TracksTheTrueTrajectoryBetterThanDeadReckoning) {
  const ObservationScene scene =
      test::squareScene(2, SensorNoise{0.0, 0.01, 0.0, 0.001}, SensorNoise{0.0, 0.02, 0.0, 0.002},
                        ProcessNoise{0.01, 0.01, 0.002});
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    const auto sim = simulation::simulateObservations(scene, seed);
    const NoiseProblem problem = makeNoiseProblem(sim.observations, sim.odometry);
    const FastSlamResult r = runFastSlam(problem, trueNoise(scene), FastSlamConfig{}, seed, 1);
    ASSERT_EQ(r.mean_trajectory.size(), sim.true_poses.size());
    Pose2 dead{};
    double err_filter = 0.0, err_dead = 0.0;
    for (std::size_t k = 0; k < sim.true_poses.size(); ++k) {
      if (k > 0) {
        const auto& u = sim.odometry[k];
        double x = 0.0, y = 0.0;
        dead.toWorld(u.dx_m, u.dy_m, x, y);
        dead = Pose2{x, y, wrapAngle(dead.yaw_rad + u.dtheta_rad)};
      }
      const Pose2& t = sim.true_poses[k];
      err_filter += std::hypot(r.mean_trajectory[k].x_m - t.x_m, r.mean_trajectory[k].y_m - t.y_m);
      err_dead += std::hypot(dead.x_m - t.x_m, dead.y_m - t.y_m);
    }
    EXPECT_LT(err_filter, 0.5 * err_dead);
    // One error sample per observation and sensor.
    EXPECT_EQ(r.errors[0].range_m.size() + r.errors[1].range_m.size(), problem.observations.size());
  }
}

TEST(FastSlam, PredictedErrorsOfNoiseFreeReadingsWithExactOdometryAreZero) {
  const ObservationScene scene = test::squareScene(1, SensorNoise{0.0, 0.0, 0.0, 0.0},
                                                   SensorNoise{0.0, 0.0, 0.0, 0.0}, ProcessNoise{});
  const auto sim = simulation::simulateObservations(scene, 1);
  NoiseSetting assumed = trueNoise(scene);
  for (auto& s : assumed.sensors) s = SensorNoise{0.0, 0.01, 0.0, 0.01};
  const FastSlamResult r = runFastSlam(makeNoiseProblem(sim.observations, sim.odometry), assumed,
                                       FastSlamConfig{}, 1, 1);
  for (const auto& e : r.errors)
    for (std::size_t i = 0; i < e.range_m.size(); ++i) {
      EXPECT_NEAR(e.range_m[i], 0.0, 1e-9);
      EXPECT_NEAR(e.bearing_rad[i], 0.0, 1e-9);
    }
}

TEST(FastSlam, SkippingInitialisingReadingsDropsOneSamplePerLandmark) {
  const ObservationScene scene = test::squareScene(
      1, SensorNoise{0.0, 0.04, 0.0, 0.01}, SensorNoise{0.0, 0.04, 0.0, 0.01}, ProcessNoise{});
  const auto sim = simulation::simulateObservations(scene, 1);
  const NoiseProblem problem = makeNoiseProblem(sim.observations, sim.odometry);
  FastSlamConfig config;
  config.particles = 5;
  const auto all = runFastSlam(problem, trueNoise(scene), config, 1, 1);
  config.skip_initialising = true;
  const auto skipped = runFastSlam(problem, trueNoise(scene), config, 1, 1);
  const std::size_t n_all = all.errors[0].range_m.size() + all.errors[1].range_m.size();
  const std::size_t n_skipped = skipped.errors[0].range_m.size() + skipped.errors[1].range_m.size();
  EXPECT_EQ(n_all - n_skipped, static_cast<std::size_t>(problem.landmarks));
}

}  // namespace
}  // namespace lidarcal::noise
