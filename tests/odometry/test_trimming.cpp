// SPDX-License-Identifier: BSD-3-Clause
// Outlier trimming: the nearest-rank percentile against its definition, and a round that drops
// injected scan-matching failures and keeps the rest.

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "common/rng.hpp"
#include "odometry/simulated_samples.hpp"
#include "odometry/trimming.hpp"

namespace lidarcal::odometry {
namespace {

TEST(Trimming, NearestRankPercentileFollowsItsDefinition) {
  // Oracle: sort, take the value at rank ceil(p/100 n) (1-based).
  std::mt19937_64 rng = makeRng(3, 0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const std::size_t n : {1u, 2u, 7u, 100u, 101u, 3295u}) {
    std::vector<double> v(n);
    for (double& x : v) x = unit(rng);
    std::vector<double> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    for (const double p : {50.5, 90.0, 99.0, 100.0}) {
      const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(n)));
      EXPECT_EQ(nearestRankPercentile(v, p), sorted[std::max<std::size_t>(rank, 1) - 1])
          << "n " << n << " p " << p;
    }
  }
  // 99th of 3295: rank 3263, so 32 values lie above it.
  std::vector<double> ramp(3295);
  std::iota(ramp.begin(), ramp.end(), 1.0);
  EXPECT_EQ(nearestRankPercentile(ramp, 99.0), 3263.0);
}

std::vector<std::size_t> all(std::size_t n) {
  std::vector<std::size_t> i(n);
  std::iota(i.begin(), i.end(), std::size_t{0});
  return i;
}

TEST(Trimming, ARoundDropsTheScanMatchingFailuresFirst) {
  SimulationSettings settings;
  settings.samples = 1000;
  std::vector<OdometrySample> samples = simulateSamples(settings);
  // Ten failures, each far off in translation or in rotation only.
  const std::set<std::size_t> failed = {3, 77, 150, 299, 400, 512, 640, 777, 888, 999};
  bool rotation = false;
  for (const std::size_t i : failed) {
    (rotation ? samples[i].scan_match_theta_rad : samples[i].scan_match_y_m) += 0.3;
    rotation = !rotation;
  }
  const std::vector<std::size_t> kept =
      trimRound(samples, all(samples.size()), settings.truth, 99.0);
  for (const std::size_t i : failed)
    EXPECT_FALSE(std::binary_search(kept.begin(), kept.end(), i)) << i;
  // At most 1 % dropped per criterion: here the ten failures and up to 10 + 10 inliers.
  EXPECT_GE(kept.size(), 1000u - 20u);
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
}

TEST(Trimming, TheHundredthPercentileKeepsEverySample) {
  const std::vector<OdometrySample> samples = simulateSamples(SimulationSettings{});
  EXPECT_EQ(trimRound(samples, all(samples.size()), SimulationSettings{}.truth, 100.0).size(),
            samples.size());
  EXPECT_TRUE(trimRound(samples, {}, SimulationSettings{}.truth, 99.0).empty());
}

TEST(Trimming, ARoundKeepsTheOrderAndOnlyTheListedSamples) {
  const std::vector<OdometrySample> samples = simulateSamples(SimulationSettings{});
  const std::vector<std::size_t> some = {900, 5, 17, 400, 401, 2};
  const std::vector<std::size_t> kept = trimRound(samples, some, SimulationSettings{}.truth, 99.0);
  // n = 6: the 99th percentile is the largest value, nothing is dropped.
  EXPECT_EQ(kept, some);
}

}  // namespace
}  // namespace lidarcal::odometry
