// SPDX-License-Identifier: BSD-3-Clause
// The observation-level simulator (Sharma 2020's setting): readings, noise statistics, streams.

#include <cmath>

#include <gtest/gtest.h>

#include "noise/noise_scenes.hpp"
#include "simulation/observation_sim.hpp"

namespace lidarcal::simulation {
namespace {

TEST(ObservationSim, NoiseFreeReadingsAreTheTrueRangeAndBearingFromTheTruePose) {
  ObservationScene scene =
      test::squareScene(1, SensorNoise{}, SensorNoise{}, ProcessNoise{0.01, 0.01, 0.01});
  scene.sensors[1].max_range_m = 5.0;
  scene.sensors[1].fov_rad = kPi;
  const auto sim = simulateObservations(scene, 3);
  ASSERT_EQ(sim.odometry.size(), 1u + 4u * 6u);
  ASSERT_EQ(sim.true_poses.size(), sim.odometry.size());
  std::size_t seen1 = 0;
  for (const auto& o : sim.observations) {
    const Pose2& p = sim.true_poses[static_cast<std::size_t>(o.stop)];
    const auto& l = scene.landmarks[static_cast<std::size_t>(o.landmark)];
    EXPECT_NEAR(o.range_m, std::hypot(l.x_m - p.x_m, l.y_m - p.y_m), 1e-12);
    EXPECT_NEAR(wrapAngle(o.bearing_rad - (std::atan2(l.y_m - p.y_m, l.x_m - p.x_m) - p.yaw_rad)),
                0.0, 1e-12);
    if (o.sensor == 1) {
      ++seen1;
      EXPECT_LE(o.range_m, 5.0);
      EXPECT_LE(std::abs(o.bearing_rad), kPi / 2);
    }
  }
  EXPECT_GT(seen1, 0u);
  EXPECT_LT(seen1, sim.observations.size() / 2);
  // Process noise: the true path leaves the commanded one.
  EXPECT_GT(std::hypot(sim.true_poses.back().x_m, sim.true_poses.back().y_m), 1e-3);
}

TEST(ObservationSim, ReadingErrorsHaveTheConfiguredMeanAndVariance) {
  const SensorNoise s0{0.2, 0.3, -0.05, 0.04}, s1{0.0, 0.5, 0.1, 0.01};
  const ObservationScene scene = test::squareScene(20, s0, s1, ProcessNoise{});
  const auto sim = simulateObservations(scene, 8);
  for (int s = 0; s < 2; ++s) {
    SCOPED_TRACE(s);
    const SensorNoise& n = s == 0 ? s0 : s1;
    double sr = 0, sr2 = 0, sb = 0, sb2 = 0;
    double count = 0;
    for (const auto& o : sim.observations) {
      if (o.sensor != s) continue;
      const Pose2& p = sim.true_poses[static_cast<std::size_t>(o.stop)];
      const auto& l = scene.landmarks[static_cast<std::size_t>(o.landmark)];
      const double er = o.range_m - std::hypot(l.x_m - p.x_m, l.y_m - p.y_m);
      const double eb =
          wrapAngle(o.bearing_rad - (std::atan2(l.y_m - p.y_m, l.x_m - p.x_m) - p.yaw_rad));
      sr += er, sr2 += er * er, sb += eb, sb2 += eb * eb, count += 1;
    }
    const double mr = sr / count, mb = sb / count;
    const double vr = sr2 / count - mr * mr, vb = sb2 / count - mb * mb;
    // 5 standard errors of a mean and of a variance from `count` samples.
    EXPECT_NEAR(mr, n.range_mean_m, 5 * std::sqrt(n.range_var_m2 / count));
    EXPECT_NEAR(mb, n.bearing_mean_rad, 5 * std::sqrt(n.bearing_var_rad2 / count));
    EXPECT_NEAR(vr, n.range_var_m2, 5 * n.range_var_m2 * std::sqrt(2 / count));
    EXPECT_NEAR(vb, n.bearing_var_rad2, 5 * n.bearing_var_rad2 * std::sqrt(2 / count));
  }
}

TEST(ObservationSim, ChangingOneSensorLeavesTheOthersReadingsUnchanged) {
  ObservationScene a = test::squareScene(1, SensorNoise{0.0, 0.1, 0.0, 0.1},
                                         SensorNoise{0.0, 0.2, 0.0, 0.2}, ProcessNoise{0.01, 0, 0});
  ObservationScene b = a;
  b.sensors[1].noise.range_var_m2 = 0.7;
  b.sensors[1].max_range_m = 3.0;
  const auto sa = simulateObservations(a, 4), sb = simulateObservations(b, 4);
  std::vector<Observation> a0, b0;
  for (const auto& o : sa.observations)
    if (o.sensor == 0) a0.push_back(o);
  for (const auto& o : sb.observations)
    if (o.sensor == 0) b0.push_back(o);
  ASSERT_EQ(a0.size(), b0.size());
  for (std::size_t i = 0; i < a0.size(); ++i) {
    EXPECT_EQ(a0[i].range_m, b0[i].range_m);
    EXPECT_EQ(a0[i].bearing_rad, b0[i].bearing_rad);
  }
}

}  // namespace
}  // namespace lidarcal::simulation
