// SPDX-License-Identifier: BSD-3-Clause
// The KL divergence of Sharma 2020 ch. 3.3 (closed form) and the fit of the predicted Gaussian.

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "noise/kl.hpp"

namespace lidarcal::noise {
namespace {

// KL(p || q) by numerical integration of p log(p / q) (trapezoid rule over +-12 sigma_p).
double numericKl(double mp, double vp, double mq, double vq) {
  const double sp = std::sqrt(vp), sq = std::sqrt(vq);
  const double lo = mp - 12.0 * sp, hi = mp + 12.0 * sp;
  const int n = 200000;
  const double h = (hi - lo) / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double x = lo + i * h;
    const double lp = -0.5 * (x - mp) * (x - mp) / vp - std::log(sp * std::sqrt(2.0 * M_PI));
    const double lq = -0.5 * (x - mq) * (x - mq) / vq - std::log(sq * std::sqrt(2.0 * M_PI));
    sum += (i == 0 || i == n ? 0.5 : 1.0) * std::exp(lp) * (lp - lq);
  }
  return sum * h;
}

TEST(GaussianKl, IsZeroForIdenticalGaussians) {
  for (double m : {-1.0, 0.0, 0.3})
    for (double v : {1e-4, 0.3, 5.0})
      EXPECT_DOUBLE_EQ(gaussianKl(m, v, m, v), 0.0) << m << " " << v;
}

TEST(GaussianKl, MatchesNumericalIntegration) {
  const double cases[][4] = {
      {0.0, 0.3, 0.0, 0.5}, {0.1, 0.4, -0.2, 0.2}, {0.0, 1.0, 2.0, 1.0}, {1.0, 0.01, 1.1, 0.09}};
  for (const auto& c : cases) {
    SCOPED_TRACE(testing::Message() << c[0] << " " << c[1] << " " << c[2] << " " << c[3]);
    EXPECT_NEAR(gaussianKl(c[0], c[1], c[2], c[3]), numericKl(c[0], c[1], c[2], c[3]), 1e-6);
  }
}

TEST(GaussianKl, IsAsymmetricPositiveAndInfiniteForDegenerateVariances) {
  EXPECT_GT(gaussianKl(0.0, 0.3, 0.0, 0.6), 0.0);
  EXPECT_NE(gaussianKl(0.0, 0.3, 0.0, 0.6), gaussianKl(0.0, 0.6, 0.0, 0.3));
  EXPECT_TRUE(std::isinf(gaussianKl(0.0, 0.0, 0.0, 1.0)));
  EXPECT_TRUE(std::isinf(gaussianKl(0.0, 1.0, 0.0, -1.0)));
}

TEST(FitErrors, CentralStatisticsAreTheMeanAndVarianceAndSquaredErrorsLeakTheMean) {
  const std::vector<double> e{1.0, 2.0, 3.0, 4.0};
  std::vector<double> e2;
  for (double v : e) e2.push_back(v * v);
  const ErrorGaussian central = fitErrors(e, e2, ErrorStatistic::central);
  EXPECT_DOUBLE_EQ(central.mean, 2.5);
  EXPECT_DOUBLE_EQ(central.var, 1.25);
  // Second moment about zero = variance + mean^2.
  const ErrorGaussian squared = fitErrors(e, e2, ErrorStatistic::squared_errors);
  EXPECT_DOUBLE_EQ(squared.mean, 2.5);
  EXPECT_DOUBLE_EQ(squared.var, 1.25 + 2.5 * 2.5);
}

}  // namespace
}  // namespace lidarcal::noise
