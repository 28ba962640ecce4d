// SPDX-License-Identifier: BSD-3-Clause
// The subset scatter: consecutive subsets, their statistics against a direct computation, and on
// a simulated drive (where the covariance is right) a spread that matches the stated errors.

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "odometry/simulated_samples.hpp"
#include "odometry/subsets.hpp"

namespace lidarcal::odometry {
namespace {

TEST(Subsets, SplitsIntoConsecutiveNearEqualParts) {
  SimulationSettings settings;
  settings.samples = 1003;
  const std::vector<OdometrySample> samples = simulateSamples(settings);
  const SubsetScatter s = scatterOverSubsets(samples, 4);
  ASSERT_EQ(s.first_sample.size(), 4u);
  EXPECT_EQ(s.first_sample, (std::vector<std::size_t>{0, 250, 501, 752}));
  EXPECT_EQ(s.subsets[0].samples_total, 250u);
  EXPECT_EQ(s.subsets[3].samples_total, 251u);
  // Subset 2 is the calibration of samples 250..500 alone.
  const std::vector<OdometrySample> second(samples.begin() + 250, samples.begin() + 501);
  EXPECT_EQ(s.subsets[1].estimate.toVector(), calibrateOdometry(second).estimate.toVector());
}

TEST(Subsets, TheStatisticsAreThoseOfTheSubsetsEstimates) {
  SimulationSettings settings;
  settings.samples = 1500;
  const SubsetScatter s = scatterOverSubsets(simulateSamples(settings), 3);
  ASSERT_TRUE(s.status.ok()) << s.status.message;
  ASSERT_EQ(s.subsets_ok, 3);
  for (int k = 0; k < kParameterCount; ++k) {
    double x[3], e[3];
    for (int i = 0; i < 3; ++i) {
      x[i] = s.subsets[i].estimate.toVector()[k];
      e[i] = s.subsets[i].standardErrors()[k];
    }
    const double mean = (x[0] + x[1] + x[2]) / 3.0;
    const double sd = std::sqrt(((x[0] - mean) * (x[0] - mean) + (x[1] - mean) * (x[1] - mean) +
                                 (x[2] - mean) * (x[2] - mean)) /
                                2.0);
    EXPECT_NEAR(s.mean[k], mean, 1e-12 * std::abs(mean) + 1e-18);
    EXPECT_NEAR(s.spread[k], sd, 1e-9 * sd);
    EXPECT_NEAR(s.mean_standard_error[k], (e[0] + e[1] + e[2]) / 3.0, 1e-9 * e[0]);
    EXPECT_NEAR(s.ratio[k], sd / s.mean_standard_error[k], 1e-9);
    // chi-square with 2 degrees of freedom: quantiles 0.0506 and 7.378
    EXPECT_NEAR(s.ratio_low[k] / s.ratio[k], std::sqrt(2.0 / 7.377759), 1e-5);
    EXPECT_NEAR(s.ratio_high[k] / s.ratio[k], std::sqrt(2.0 / 0.0506356), 1e-4);
  }
}

TEST(Subsets, OnASimulatedDriveTheSpreadMatchesTheStatedError) {
  // 20 subsets of 500 samples: the spread over stated ratio has a 95 % interval of about
  // 0.68-1.32 when the covariance is right; pooled over the six parameters it lies near 1.
  SimulationSettings settings;
  settings.samples = 10000;
  const SubsetScatter s = scatterOverSubsets(simulateSamples(settings), 20);
  ASSERT_TRUE(s.status.ok()) << s.status.message;
  EXPECT_EQ(s.subsets_ok, 20);
  for (int k = 0; k < kParameterCount; ++k) {
    EXPECT_GT(s.ratio[k], 0.6) << kParameterNames[k];
    EXPECT_LT(s.ratio[k], 1.4) << kParameterNames[k];
  }
  EXPECT_NEAR(s.ratio.mean(), 1.0, 0.2);
}

TEST(Subsets, InterleavedSubsetsDealEveryNthSample) {
  SimulationSettings settings;
  settings.samples = 1000;
  const std::vector<OdometrySample> samples = simulateSamples(settings);
  const SubsetScatter s = scatterOverSubsets(samples, 4, {}, SubsetSplit::interleaved);
  EXPECT_EQ(s.first_sample, (std::vector<std::size_t>{0, 1, 2, 3}));
  std::vector<OdometrySample> second;
  for (std::size_t i = 1; i < samples.size(); i += 4) second.push_back(samples[i]);
  EXPECT_EQ(s.subsets[1].estimate.toVector(), calibrateOdometry(second).estimate.toVector());
}

TEST(Subsets, ADriveInPhasesNeedsInterleavedSubsets) {
  // First turning in place, then driving straight: each half alone is degenerate.
  SimulationSettings turning, straight;
  turning.mix = {false, true, false, false};
  straight.mix = {true, false, false, false};
  straight.seed = 2;
  std::vector<OdometrySample> samples = simulateSamples(turning);
  const std::vector<OdometrySample> second = simulateSamples(straight);
  samples.insert(samples.end(), second.begin(), second.end());
  const SubsetScatter halves = scatterOverSubsets(samples, 2);
  EXPECT_EQ(halves.subsets_ok, 0);
  EXPECT_FALSE(halves.status.ok());
  const SubsetScatter dealt = scatterOverSubsets(samples, 2, {}, SubsetSplit::interleaved);
  EXPECT_EQ(dealt.subsets_ok, 2);
  EXPECT_TRUE(dealt.status.ok()) << dealt.status.message;
}

TEST(Subsets, TooFewUsableSubsetsIsAStatus) {
  SimulationSettings settings;
  settings.samples = 30;  // subsets of 10 samples: below the 12 a calibration needs
  const SubsetScatter s = scatterOverSubsets(simulateSamples(settings), 3);
  EXPECT_EQ(s.status.code, StatusCode::too_few_samples);
  EXPECT_EQ(s.subsets_ok, 0);
  EXPECT_EQ(s.subsets.size(), 3u);
  EXPECT_TRUE(s.ratio.allFinite());
}

}  // namespace
}  // namespace lidarcal::odometry
