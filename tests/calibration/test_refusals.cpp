// SPDX-License-Identifier: BSD-3-Clause
// The refusals of calibrate(): each sets its status code and a message naming what to do, and
// lets usable data through.

#include <gtest/gtest.h>

#include <vector>

#include "calibration/refusals.hpp"

namespace lidarcal {
namespace {

TEST(Refusals, ThePathExtentIsTheDiagonalOfTheStopsBoundingBox) {
  EXPECT_EQ(calibration::pathExtent({}), 0.0);
  EXPECT_NEAR(calibration::pathExtent({{0, 0, 0}, {3, 0, 1}, {3, 4, 2}}), 5.0, 1e-12);
}

TEST(Refusals, StopsWithinTheMinimumBaselineCannotTriangulate) {
  calibration::CalibrationConfig config;  // min_baseline_m 0.1
  const auto problem = calibration::baselineProblem({{0, 0, 0}, {0.03, 0.04, 1.0}}, config);
  ASSERT_TRUE(problem.has_value());
  EXPECT_NE(problem->find("2 stops lie within 0.05 m"), std::string::npos) << *problem;
  EXPECT_NE(problem->find("--reference"), std::string::npos);
  EXPECT_FALSE(calibration::baselineProblem({{0, 0, 0}, {0.2, 0, 0}}, config).has_value());
  // one stop: refused later
  EXPECT_FALSE(calibration::baselineProblem({{0, 0, 0}}, config).has_value());
}

TEST(Refusals, UnusableInputIsRefusedWithItsCode) {
  calibration::CalibrationConfig config;
  LandmarkObservations obs;
  obs.commanded = {{0, 0, 0}, {0.01, 0, 0}};
  obs.sightings.resize(1);
  CalibrationModel m;
  EXPECT_TRUE(calibration::refuseUnusableInput(m, obs, config));
  EXPECT_EQ(m.status.code, StatusCode::no_baseline);
  // A baseline, but the dark-surface term without intensities.
  obs.commanded[1].x_m = 2.0;
  config.joint.effects.dark_noise = true;
  CalibrationModel dark;
  EXPECT_TRUE(calibration::refuseUnusableInput(dark, obs, config));
  EXPECT_EQ(dark.status.code, StatusCode::no_intensity);
  config.joint.effects.dark_noise = false;
  CalibrationModel fine;
  EXPECT_FALSE(calibration::refuseUnusableInput(fine, obs, config));
  EXPECT_TRUE(fine.status.ok());
}

TEST(Refusals, ATriangulationNeedsAUsableLandmarkAndARadius) {
  CalibrationModel none;
  EXPECT_TRUE(calibration::refuseTriangulation(none, {}, 0, 0.05));
  EXPECT_EQ(none.status.code, StatusCode::no_usable_landmark);
  EXPECT_NE(none.status.message.find("no landmark was observed"), std::string::npos);
  CalibrationModel no_radius;
  EXPECT_TRUE(calibration::refuseTriangulation(no_radius, {}, 2, 0.0));
  EXPECT_EQ(no_radius.status.code, StatusCode::no_radius);
  CalibrationModel fine;
  EXPECT_FALSE(calibration::refuseTriangulation(fine, {}, 2, 0.05));
}

TEST(Refusals, TooFewPairsForTheOrdersAreRefusedWithTheCountNeeded) {
  calibration::CalibrationConfig config;  // max_order 4: 7 pairs needed
  LandmarkObservations obs;
  CalibrationModel m;
  EXPECT_TRUE(calibration::refuseTooFewPairs(m, obs, config, {}, 6, 2));
  EXPECT_EQ(m.status.code, StatusCode::too_few_observations);
  EXPECT_NE(m.status.message.find(
                "only 6 landmark-stop distances from 2 triangulated landmarks (at least 7 needed)"),
            std::string::npos)
      << m.status.message;
  CalibrationModel fine;
  EXPECT_FALSE(calibration::refuseTooFewPairs(fine, obs, config, {}, 7, 2));
}

TEST(Refusals, AJointFitThatPlacesALandmarkBeyondTheSensorsRangeRanAway) {
  LandmarkObservations obs;
  obs.range_max_m = 4.0;  // limit 1.5 x 4 + 0.5 = 6.5 m
  calibration::JointResult j;
  j.status.code = StatusCode::ok;
  j.model.bias = BiasPolynomial{{0.0, 1.0}};
  j.distances_m = {1.0, 6.0};
  CalibrationModel fine;
  EXPECT_FALSE(calibration::refuseJoint(fine, j, obs, 3, 2.0));
  j.distances_m = {1.0, 7.0};
  CalibrationModel away;
  EXPECT_TRUE(calibration::refuseJoint(away, j, obs, 3, 2.0));
  EXPECT_EQ(away.status.code, StatusCode::joint_failed);
  EXPECT_NE(away.status.message.find("ran away"), std::string::npos);
  j.distances_m = {0.0, 2.0};
  CalibrationModel collapsed;
  EXPECT_TRUE(calibration::refuseJoint(collapsed, j, obs, 3, 2.0));
  EXPECT_NE(collapsed.status.message.find("collapsed"), std::string::npos);
}

}  // namespace
}  // namespace lidarcal
