// SPDX-License-Identifier: BSD-3-Clause
// The oracle against known distances: noise-free readings of a known bias give it back, and too
// few readings are a status, not a throw.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "calibration/oracle.hpp"
#include "common/rng.hpp"

namespace lidarcal {
namespace {

std::vector<calibration::RangePair> pairsOf(const BiasPolynomial& f, double sigma_e, int n,
                                            std::uint64_t seed) {
  auto rng = makeRng(seed, 0);
  std::uniform_real_distribution<double> dist(0.5, 6.0);
  std::normal_distribution<double> e(0.0, 1.0);
  std::vector<calibration::RangePair> pairs;
  for (int i = 0; i < n; ++i) {
    const double d = dist(rng);
    pairs.push_back({d, f(d) + sigma_e * f(d) * f(d) * e(rng), i % 3});
  }
  return pairs;
}

TEST(Oracle, NearlyNoiseFreeReadingsOfAStraightBiasGiveItBack) {
  const BiasPolynomial f{{0.02, 1.03}};
  calibration::CalibrationConfig config;
  config.max_order = 2;
  const CalibrationModel m = calibration::calibrateAgainstTruth(pairsOf(f, 1e-7, 600, 3), config);
  ASSERT_TRUE(m.status.ok()) << m.status.message;
  EXPECT_EQ(m.method, "oracle");
  ASSERT_GE(m.model.bias.alpha.size(), 2u);
  EXPECT_NEAR(m.model.bias(1.0), f(1.0), 1e-5);
  EXPECT_NEAR(m.model.bias(5.0), f(5.0), 1e-5);
  EXPECT_EQ(m.readings, 600u);
}

TEST(Oracle, TheSquaredLawsSigmaIsRecoveredWithinItsStandardError) {
  const BiasPolynomial f{{0.01, 0.98}};
  calibration::CalibrationConfig config;
  config.max_order = 2;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    const double sigma_e = 0.003;
    const CalibrationModel m =
        calibration::calibrateAgainstTruth(pairsOf(f, sigma_e, 5000, seed), config);
    ASSERT_TRUE(m.status.ok());
    EXPECT_NEAR(m.model.noise.sigma_e, sigma_e, 4.0 * sigma_e / std::sqrt(2.0 * 5000));
  }
}

TEST(Oracle, TooFewReadingsAreAStatus) {
  calibration::CalibrationConfig config;  // max_order 4: 7 needed
  const CalibrationModel m =
      calibration::calibrateAgainstTruth(pairsOf(BiasPolynomial{}, 0.0, 6, 1), config);
  EXPECT_EQ(m.status.code, StatusCode::too_few_observations);
}

}  // namespace
}  // namespace lidarcal
