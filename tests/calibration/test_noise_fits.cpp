// SPDX-License-Identifier: BSD-3-Clause
// The noise law of a fitted bias recovered from readings the test draws, and the side estimators
// that fail on degenerate data noted, never thrown.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "calibration/noise_fits.hpp"
#include "common/rng.hpp"

namespace lidarcal {
namespace {

TEST(NoiseFits, TheSquaredAndConstantLawsRecoverTheirSigmaFromDrawnReadings) {
  const BiasPolynomial f{{0.01, 1.02}};
  for (int seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    auto rng = makeRng(seed, 0);
    std::uniform_real_distribution<double> dist(0.5, 5.0);
    std::normal_distribution<double> e(0.0, 1.0);
    const double sigma_e = 0.004;
    std::vector<double> d, y_sq, y_const;
    for (int i = 0; i < 20000; ++i) {
      d.push_back(dist(rng));
      y_sq.push_back(f(d.back()) + sigma_e * f(d.back()) * f(d.back()) * e(rng));
      y_const.push_back(f(d.back()) + 0.01 * e(rng));
    }
    const NoiseModel sq = calibration::fitNoiseLaw(NoiseKind::squared, 1, f, d, y_sq);
    EXPECT_EQ(sq.kind, NoiseKind::squared);
    EXPECT_NEAR(sq.sigma_e, sigma_e, 4.0 * sigma_e / std::sqrt(2.0 * 20000));  // 4 standard errors
    const NoiseModel c = calibration::fitNoiseLaw(NoiseKind::constant, 1, f, d, y_const);
    EXPECT_NEAR(c.sigma_e, 0.01, 4.0 * 0.01 / std::sqrt(2.0 * 20000));
  }
}

TEST(NoiseFits, ALawWithoutAFitIsRefused) {
  EXPECT_THROW(calibration::fitNoiseLaw(NoiseKind::power, 1, BiasPolynomial{}, {1.0}, {1.0}),
               std::invalid_argument);
}

TEST(NoiseFits, EstimatorsThatCannotRunAreNotedAndTheResultDoesNotDependOnTheThreads) {
  CalibrationModel m;
  m.model.bias = BiasPolynomial{{0.0, 1.0}};
  calibration::fillNoiseFits(m, 1, {1.0}, {1.0}, {}, 1);  // one reading: nothing to fit
  EXPECT_FALSE(m.noise_fits.unavailable.empty());
  EXPECT_EQ(m.noise_fits.exponent_best, -1);
  // Enough readings: the same fields whatever the thread count.
  auto rng = makeRng(7, 0);
  std::normal_distribution<double> e(0.0, 0.01);
  std::vector<double> d, y;
  for (int i = 0; i < 300; ++i) {
    d.push_back(0.5 + 0.01 * i);
    y.push_back(d.back() + e(rng));
  }
  CalibrationModel one = m, two = m;
  calibration::fillNoiseFits(one, 1, d, y, {}, 1);
  calibration::fillNoiseFits(two, 1, d, y, {}, 2);
  EXPECT_EQ(one.noise_fits.alhashimi2021_beta, two.noise_fits.alhashimi2021_beta);
  EXPECT_EQ(one.noise_fits.alhashimi2016_cf_alpha, two.noise_fits.alhashimi2016_cf_alpha);
  EXPECT_EQ(one.noise_fits.alhashimi2016_ml_alpha, two.noise_fits.alhashimi2016_ml_alpha);
  EXPECT_EQ(one.noise_fits.unavailable, two.noise_fits.unavailable);
  EXPECT_EQ(one.noise_fits.unavailable.count("alhashimi2016_closed_form"), 0u);
}

}  // namespace
}  // namespace lidarcal
