// SPDX-License-Identifier: BSD-3-Clause
// The simulator of samples: deterministic for a seed, noise-free samples obey the motion model,
// each motion kind is what it says, and the noise has the stated spread.

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "odometry/simulated_samples.hpp"

namespace lidarcal::odometry {
namespace {

TEST(SimulatedSamples, AreDeterministicForASeed) {
  SimulationSettings a;
  a.samples = 50;
  const auto first = simulateSamples(a), again = simulateSamples(a);
  a.seed = 2;
  const auto other = simulateSamples(a);
  ASSERT_EQ(first.size(), 50u);
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(first[i].scan_match_x_m, again[i].scan_match_x_m);
    EXPECT_EQ(first[i].left_wheel_rad_s, again[i].left_wheel_rad_s);
  }
  EXPECT_NE(first[0].scan_match_x_m, other[0].scan_match_x_m);
}

TEST(SimulatedSamples, EachMotionKindIsWhatItSays) {
  SimulationSettings s;
  s.samples = 200;
  s.mix = {true, false, false, false};
  for (const auto& x : simulateSamples(s)) EXPECT_EQ(x.left_wheel_rad_s, x.right_wheel_rad_s);
  s.mix = {false, true, false, false};
  for (const auto& x : simulateSamples(s)) EXPECT_EQ(x.left_wheel_rad_s, -x.right_wheel_rad_s);
  s.mix = {false, false, true, false};
  for (const auto& x : simulateSamples(s))
    EXPECT_TRUE(x.left_wheel_rad_s == 0.0 || x.right_wheel_rad_s == 0.0);
  s.mix = {false, false, false, true};
  for (const auto& x : simulateSamples(s)) {
    EXPECT_GT(x.left_wheel_rad_s * x.right_wheel_rad_s, 0.0);
    EXPECT_NE(x.left_wheel_rad_s, x.right_wheel_rad_s);
  }
  s.mix = {false, false, false, false};
  EXPECT_THROW(simulateSamples(s), std::invalid_argument);
}

TEST(SimulatedSamples, NoiseHasTheStatedSpreadAboutTheModel) {
  SimulationSettings s;
  s.samples = 20000;
  s.sigma_x_m = 0.002;
  s.sigma_y_m = 0.001;
  s.sigma_theta_rad = 0.004;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), squares = Eigen::Vector3d::Zero();
  for (const auto& x : simulateSamples(s)) {
    const Eigen::Vector3d e = scanMatchResidual(s.truth, x);
    sum += e;
    squares += e.cwiseProduct(e);
  }
  const Eigen::Vector3d sd = (squares / 20000.0).cwiseSqrt();
  // Standard error of a standard deviation from 20000 draws: 0.5 %; allow 2 %.
  EXPECT_NEAR(sd[0], 0.002, 0.02 * 0.002);
  EXPECT_NEAR(sd[1], 0.001, 0.02 * 0.001);
  EXPECT_NEAR(sd[2], 0.004, 0.02 * 0.004);
  EXPECT_LT(std::abs(sum[0] / 20000.0), 4.0 * 0.002 / std::sqrt(20000.0));
}

}  // namespace
}  // namespace lidarcal::odometry
