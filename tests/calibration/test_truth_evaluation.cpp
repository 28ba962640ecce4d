// SPDX-License-Identifier: BSD-3-Clause
// Scoring against a simulator's truth: the odometry scale error of a path the test scales and
// moves, and a truth that does not describe the sequence refused.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "calibration/truth_evaluation.hpp"
#include "common/errors.hpp"
#include "io/scene_io.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

TEST(TruthEvaluation, TheCommandedScaleIsTheScaleOfTheCommandedPathOverTheActualOne) {
  for (const double scale : {0.97, 1.0, 1.05}) {
    SCOPED_TRACE(scale);
    Truth t;
    for (int k = 0; k < 6; ++k) {
      TruthStop s;
      s.actual = Pose2{0.3 * k, 0.1 * k * k, 0.2 * k};
      // The commanded path: the actual one scaled, turned by 0.4 rad and moved (a similarity).
      const double c = std::cos(0.4), sn = std::sin(0.4);
      s.commanded =
          Pose2{2.0 + scale * (c * s.actual.x_m - sn * s.actual.y_m),
                -1.0 + scale * (sn * s.actual.x_m + c * s.actual.y_m), s.actual.yaw_rad + 0.4};
      t.stops.push_back(s);
    }
    EXPECT_NEAR(calibration::commandedScale(t), scale, 1e-9);
  }
  Truth one;
  one.stops.resize(1);
  EXPECT_EQ(calibration::commandedScale(one), 1.0);  // no path to scale
}

TEST(TruthEvaluation, ATruthOfAnotherSequenceIsRefused) {
  const io::Sequence seq = io::openSequence(test::sourceDir() / "data/example/scans");
  io::SimulationTruth other = io::loadTruth(test::sourceDir() / "data/example/truth.json");
  other.ranges.resize(other.ranges.size() - other.beams);  // one scan fewer
  EXPECT_THROW(calibration::truthPairs(seq, other, 1.0), InputError);
  EXPECT_THROW(calibration::truthBatches(seq, other), InputError);
}

TEST(TruthEvaluation, TheOraclesPairsAreTheTrueDistancesOfTheLandmarkBeamsTimesTheScale) {
  const io::Sequence seq = io::openSequence(test::sourceDir() / "data/example/scans");
  const io::SimulationTruth truth = io::loadTruth(test::sourceDir() / "data/example/truth.json");
  const auto plain = calibration::truthPairs(seq, truth, 1.0);
  const auto scaled = calibration::truthPairs(seq, truth, 1.1);
  ASSERT_FALSE(plain.empty());
  ASSERT_EQ(plain.size(), scaled.size());
  const RangeModel& sensor = truth.truth.scene.sensor.range;
  for (std::size_t i = 0; i < plain.size(); ++i) {
    EXPECT_NEAR(scaled[i].d_m, 1.1 * plain[i].d_m, 1e-12);
    EXPECT_EQ(scaled[i].y_m, plain[i].y_m);
    // Each reading is the simulated sensor's at its true distance: f(d) within 6 of its sigmas.
    const double d = plain[i].d_m;
    EXPECT_LT(std::abs(plain[i].y_m - sensor.bias(d)), 6.0 * sensor.noise.stddev(d, sensor.bias))
        << d;
  }
}

}  // namespace
}  // namespace lidarcal
