// SPDX-License-Identifier: BSD-3-Clause
// The diagnosis' statistics (diagnosis/stats.hpp) against closed forms and their definitions:
// Holm's step-down, likelihood-ratio and combined p-values, the KS distance, replica p-values,
// the reading-grid resultant, the held-out p-value.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "calibration/joint_refinement.hpp"
#include "common/rng.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

TEST(DiagnoseStats, LikelihoodRatioAndCombinedPValues) {
  // Chi-square with one degree of freedom: the tabulated 5 % and 1 % points.
  EXPECT_NEAR(likelihoodRatioPValue(3.841459, 1), 0.05, 1e-6);
  EXPECT_NEAR(likelihoodRatioPValue(6.634897, 1), 0.01, 1e-6);
  EXPECT_EQ(likelihoodRatioPValue(-0.5, 1), 1.0);
  EXPECT_TRUE(std::isnan(likelihoodRatioPValue(10.0, 3)));  // one parameter only
  // On the bound of its range the null is half 0, half chi-square: its 5 % and 1 % points are
  // chi-square's 10 % and 2 % points.
  EXPECT_NEAR(boundedLikelihoodRatioPValue(2.705543), 0.05, 1e-6);
  EXPECT_NEAR(boundedLikelihoodRatioPValue(5.411894), 0.01, 1e-6);
  EXPECT_EQ(boundedLikelihoodRatioPValue(0.0), 1.0);
  // Bonferroni over the tests that apply.
  EXPECT_NEAR(combinedPValue(0.2, 0.01, 0.003), 0.009, 1e-15);
  EXPECT_NEAR(combinedPValue(0.2, 0.01, std::nan("")), 0.02, 1e-15);
  EXPECT_NEAR(combinedPValue(0.9, 0.8, 0.7), 1.0, 1e-15);
  EXPECT_TRUE(std::isnan(combinedPValue(std::nan(""), std::nan(""), std::nan(""))));
}

TEST(DiagnoseStats, KolmogorovSmirnovDistance) {
  EXPECT_DOUBLE_EQ(ksDistance({1, 2, 3}, {1, 2, 3}), 0.0);
  EXPECT_DOUBLE_EQ(ksDistance({1, 2, 3}, {4, 5, 6}), 1.0);
  EXPECT_NEAR(ksDistance({1, 2, 3, 4}, {3, 4, 5, 6}), 0.5, 1e-12);
}

TEST(DiagnoseStats, ReplicaPValueIsCalibratedForNormalStatistics) {
  // Over many draws of (statistic, 19 replicas) from one normal law, p < 0.05 about 5 % of the
  // time.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(3.0, 2.0);
  int below = 0;
  constexpr int kTrials = 4000;
  for (int t = 0; t < kTrials; ++t) {
    std::vector<double> r(19);
    for (double& v : r) v = n(rng);
    below += replicaPValue(n(rng), r, true) < 0.05;
  }
  EXPECT_NEAR(static_cast<double>(below) / kTrials, 0.05, 0.012);
  double es = 0.0;
  EXPECT_LT(replicaPValue(100.0, {0, 1, -1, 0.5, -0.5}, false, &es), 1e-4);
  EXPECT_GT(es, 50.0);
  EXPECT_GT(replicaPValue(-100.0, {0, 1, -1, 0.5, -0.5}, false), 0.99);  // one-sided: below is fine
}

TEST(DiagnoseStats, GridResultantTellsQuantisedReadings) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(1.0, 3.0);
  std::vector<double> cont, grid;
  for (int i = 0; i < 5000; ++i) {
    cont.push_back(u(rng));
    grid.push_back(quantise(cont.back(), 1e-3));
  }
  EXPECT_GT(gridResultant(grid, 1e-3), 0.999);
  EXPECT_LT(gridResultant(cont, 1e-3), 0.05);
  // a coarser grid than the readings' (half on it, half between)
  EXPECT_LT(gridResultant(grid, 2e-3), 0.05);
}

TEST(DiagnoseStats, HeldOutPValue) {
  EXPECT_DOUBLE_EQ(heldoutPValue(-0.1, 0.01), 1.0);
  EXPECT_NEAR(heldoutPValue(0.02, 0.01), 0.5 * std::erfc(2.0 / std::sqrt(2.0)), 1e-12);
  EXPECT_TRUE(std::isnan(heldoutPValue(0.02, 0.0)));
}

}  // namespace
}  // namespace lidarcal::diagnosis
