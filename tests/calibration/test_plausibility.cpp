// SPDX-License-Identifier: BSD-3-Clause
// Plausibility warnings of a self-calibrated model (calibration/calibrate.hpp,
// addPlausibilityWarnings): each fires on the condition it names and stays silent otherwise.

#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "calibration/calibrate.hpp"

namespace lidarcal::calibration {
namespace {

CalibrationModel withBias(std::vector<double> alpha, double lo, double hi) {
  CalibrationModel m;
  m.model.bias.alpha = std::move(alpha);
  m.fitted_range_m = std::make_pair(lo, hi);
  return m;
}

bool mentions(const CalibrationModel& m, const std::string& what) {
  for (const auto& w : m.warnings)
    if (w.find(what) != std::string::npos) return true;
  return false;
}

TEST(PlausibilityWarnings, TheStronglyBiasedSimulatedSensorOfThePaperIsNotFlagged) {
  // Alhashimi et al. 2021's simulated triangulation sensor over the distances its field test
  // covers: +17 % at 4.9 m, a real bias, not a sign of wrong landmarks.
  CalibrationModel m = withBias({0.0525, 0.8838, 0.0584}, 0.6, 4.9);
  addPlausibilityWarnings(m, nullptr);
  EXPECT_TRUE(m.warnings.empty()) << m.warnings.front();
}

TEST(PlausibilityWarnings, CorrectionsBeyondAQuarterOfTheDistanceAreFlaggedWithWhereTheyPeak) {
  // 0.3 m too long everywhere: 30 % at 1 m, the worst point of a range that starts at 1 m.
  CalibrationModel m = withBias({0.3, 1.0}, 1.0, 3.0);
  addPlausibilityWarnings(m, nullptr);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_TRUE(mentions(m, "30 %")) << m.warnings.front();
  EXPECT_TRUE(mentions(m, "at 1.00 m")) << m.warnings.front();
  // The same model over a range it does not reach 25 % in (20 % at 1.5 m): silent.
  CalibrationModel far = withBias({0.3, 1.0}, 1.5, 3.0);
  addPlausibilityWarnings(far, nullptr);
  EXPECT_TRUE(far.warnings.empty());
}

TEST(PlausibilityWarnings, AnOffsetThatTradesOffAgainstTheRadiusIsFlaggedOnlyWhenCorrelated) {
  for (const double corr : {0.5, -0.5, 0.95, -0.95}) {
    SCOPED_TRACE(corr);
    CalibrationModel m = withBias({0.01, 1.0}, 1.0, 3.0);
    const double var_a0 = 1e-6, var_r = 4e-6;
    m.alpha_covariance = {var_a0, 0.0, 0.0, 1e-6};
    JointResult j;
    j.radius_m = 0.05;
    j.radius_variance = var_r;
    j.alpha_radius_covariance = Eigen::Vector2d(corr * std::sqrt(var_a0 * var_r), 0.0);
    addPlausibilityWarnings(m, &j);
    EXPECT_NEAR(m.offset_radius_correlation, corr, 1e-12);
    EXPECT_EQ(mentions(m, "trades off against the estimated pole radius"), std::abs(corr) > 0.9);
  }
}

TEST(PlausibilityWarnings, LandmarksTheDataDoNotLocateAreFlaggedByTheirMedianCentreError) {
  // Standard errors along the worse axis of 5 mm to 3 m; the median decides (one badly seen
  // landmark among well located ones is not a reason to distrust the offset).
  for (const double worst_axis : {0.005, 0.05, 0.2, 3.0}) {
    SCOPED_TRACE(worst_axis);
    CalibrationModel m = withBias({0.01, 1.0}, 1.0, 3.0);
    JointResult j;
    const Eigen::Rotation2Dd turn(0.7);
    const Eigen::Matrix2d axes =
        Eigen::Vector2d(0.004 * 0.004, worst_axis * worst_axis).asDiagonal();
    for (int id = 1; id <= 4; ++id)
      j.centre_covariance[id] =
          turn.toRotationMatrix() * axes * turn.toRotationMatrix().transpose();
    j.centre_covariance[5] = Eigen::Matrix2d::Identity() * 100.0;  // one landmark 10 m uncertain
    addPlausibilityWarnings(m, &j);
    EXPECT_EQ(mentions(m, "not pinned down by the data"), worst_axis > kUnlocatedLandmarkM);
  }
}

}  // namespace
}  // namespace lidarcal::calibration
