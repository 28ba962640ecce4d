// SPDX-License-Identifier: BSD-3-Clause
// The self-starting tests of shift_history.hpp against draws whose law the test sets: checks
// s_k = b + e_k, e_k ~ N(0, phi^2 C_k), with b, phi and C_k unknown to the record.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "watch/shift_history.hpp"

namespace lidarcal::watch {
namespace {

struct Draws {
  std::mt19937_64 rng;
  std::normal_distribution<double> normal{0.0, 1.0};
  /// A covariance of its own for each check: scales 0.5-3 mm, correlation -0.8..0.8.
  Eigen::Matrix2d covariance() {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double a = 0.0005 + 0.0025 * u(rng), c = 0.0005 + 0.0025 * u(rng);
    const double rho = -0.8 + 1.6 * u(rng);
    Eigen::Matrix2d m;
    m << a * a, rho * a * c, rho * a * c, c * c;
    return m;
  }
  Shift draw(const Eigen::Vector2d& b, double phi) {
    Shift s;
    s.c = covariance();
    const Eigen::Matrix2d l = s.c.llt().matrixL();
    s.s = b + phi * l * Eigen::Vector2d(normal(rng), normal(rng));
    return s;
  }
};

TEST(ShiftHistory, TheChangeTestHasItsLevelWhateverTheBiasAndScale) {
  // 4000 records of 2-20 checks; the fraction of p-values below each level is that level
  // within four binomial standard deviations.
  Draws d{std::mt19937_64(11)};
  const Eigen::Vector2d b(0.004, -0.002);  // the fit's own bias: 4 and -2 mm
  const double phi = 1.7;                  // the fits state their scatter 1.7 times too small
  int below_05 = 0, below_01 = 0;
  const int trials = 4000;
  for (int t = 0; t < trials; ++t) {
    ShiftHistory h(50);
    const int n = 2 + t % 19;
    for (int k = 0; k < n; ++k) h.add(d.draw(b, phi));
    const FTest f = h.change(d.draw(b, phi));
    below_05 += f.p < 0.05;
    below_01 += f.p < 0.01;
    EXPECT_DOUBLE_EQ(f.dof2, 2.0 * (n - 1));
  }
  EXPECT_NEAR(below_05 / double(trials), 0.05, 4.0 * std::sqrt(0.05 * 0.95 / trials));
  EXPECT_NEAR(below_01 / double(trials), 0.01, 4.0 * std::sqrt(0.01 * 0.99 / trials));
}

TEST(ShiftHistory, KeepsItsLevelWhenStretchesAddASpreadOfTheirOwn) {
  // Each check's shift also moves by what its stretch adds (u_k ~ N(0, tau^2 I), tau = 2 mm,
  // larger than most checks' own standard errors): the record's tau^2 absorbs it. Records of
  // 5-30 checks, 3000 draws.
  Draws d{std::mt19937_64(16)};
  const Eigen::Vector2d b(-0.003, 0.001);
  const double tau = 0.002;
  auto drawSpread = [&] {
    Shift s = d.draw(b, 1.0);
    s.s += tau * Eigen::Vector2d(d.normal(d.rng), d.normal(d.rng));
    return s;
  };
  int below_05 = 0;
  const int trials = 3000;
  for (int t = 0; t < trials; ++t) {
    ShiftHistory h(50);
    for (int k = 0; k < 5 + t % 26; ++k) h.add(drawSpread());
    below_05 += h.change(drawSpread()).p < 0.05;
  }
  EXPECT_NEAR(below_05 / double(trials), 0.05, 4.0 * std::sqrt(0.05 * 0.95 / trials));
}

TEST(ShiftHistory, AChangeOfAFewStandardErrorsIsFound) {
  Draws d{std::mt19937_64(12)};
  const Eigen::Vector2d b(0.004, -0.002);
  int found = 0;
  for (int t = 0; t < 200; ++t) {
    ShiftHistory h(50);
    for (int k = 0; k < 20; ++k) h.add(d.draw(b, 1.0));
    Shift now = d.draw(b, 1.0);
    now.s += Eigen::Vector2d(0.02, 0.02);  // 20 mm at both distances: 7 standard errors or more
    found += h.change(now).p < 1e-3;
  }
  EXPECT_GE(found, 195);
}

TEST(ShiftHistory, TheAbsoluteTestHasItsLevelWhenTheFitIsUnbiased) {
  Draws d{std::mt19937_64(13)};
  int below_05 = 0;
  const int trials = 4000;
  for (int t = 0; t < trials; ++t) {
    ShiftHistory h(50);
    for (int k = 0; k < 5; ++k) h.add(d.draw(Eigen::Vector2d::Zero(), 1.4));
    below_05 += h.absolute(Eigen::Matrix2d::Zero()).p < 0.05;
  }
  EXPECT_NEAR(below_05 / double(trials), 0.05, 4.0 * std::sqrt(0.05 * 0.95 / trials));
}

TEST(ShiftHistory, TwoRecordsOfOneLawHaveTheSameMeanAtTheLevel) {
  // Checks before an alarm (5-20) and after it (1-10), drawn with one bias, scale and spread
  // (unknown to the records): the same-mean test rejects at its level. 4000 pairs.
  Draws d{std::mt19937_64(17)};
  const Eigen::Vector2d b(0.003, -0.001);
  const double phi = 1.6, tau = 0.001;
  auto draw = [&] {
    Shift s = d.draw(b, phi);
    s.s += tau * Eigen::Vector2d(d.normal(d.rng), d.normal(d.rng));
    return s;
  };
  int below_05 = 0, below_01 = 0;
  const int trials = 4000;
  for (int t = 0; t < trials; ++t) {
    ShiftHistory before(50), after(50);
    for (int k = 0; k < 5 + t % 16; ++k) before.add(draw());
    for (int k = 0; k < 1 + t % 10; ++k) after.add(draw());
    const double p = after.sameMean(before).p;
    below_05 += p < 0.05;
    below_01 += p < 0.01;
  }
  EXPECT_NEAR(below_05 / double(trials), 0.05, 4.0 * std::sqrt(0.05 * 0.95 / trials));
  EXPECT_NEAR(below_01 / double(trials), 0.01, 4.0 * std::sqrt(0.01 * 0.99 / trials));
}

TEST(ShiftHistory, ASensorChangedAfterTheAlarmHasAnotherMean) {
  // 20 mm at both distances against checks of 0.5-3 mm: found from the first check after.
  Draws d{std::mt19937_64(18)};
  const Eigen::Vector2d b(0.004, -0.002);
  int found = 0;
  for (int t = 0; t < 200; ++t) {
    ShiftHistory before(50), after(50);
    for (int k = 0; k < 10; ++k) before.add(d.draw(b, 1.0));
    after.add(d.draw(b + Eigen::Vector2d(0.02, 0.02), 1.0));
    found += after.sameMean(before).p < 1e-3;
  }
  EXPECT_GE(found, 195);
}

TEST(ShiftHistory, AModelOfAnotherSensorFailsTheAbsoluteTest) {
  Draws d{std::mt19937_64(14)};
  ShiftHistory h(50);
  for (int k = 0; k < 5; ++k) h.add(d.draw(Eigen::Vector2d(0.03, 0.05), 1.0));
  EXPECT_LT(h.absolute(Eigen::Matrix2d::Zero()).p, 1e-3);
  // The model's own error, when large, explains the shift away.
  EXPECT_GT(h.absolute(Eigen::Matrix2d::Identity() * 0.1).p, 0.5);
}

TEST(ShiftHistory, KeepsItsCapacityAndNeedsTwoChecks) {
  ShiftHistory h(3);
  Draws d{std::mt19937_64(15)};
  EXPECT_THROW(h.change(d.draw(Eigen::Vector2d::Zero(), 1.0)), std::logic_error);
  for (int k = 0; k < 10; ++k) h.add(d.draw(Eigen::Vector2d::Zero(), 1.0));
  EXPECT_EQ(h.size(), 3u);
  EXPECT_THROW(ShiftHistory(1), std::invalid_argument);
}

}  // namespace
}  // namespace lidarcal::watch
