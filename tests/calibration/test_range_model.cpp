// SPDX-License-Identifier: BSD-3-Clause
// Range-model fits: least squares, AIC on a hand-computable case, Alhashimi et al. 2016's closed
// form against its formula, ML, Alhashimi et al. 2021's noise polynomial, the noise-exponent test.

#include <cmath>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "calibration/noise_exponent.hpp"
#include "calibration/range_model_fit.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

TEST(FitPolynomial, RecoversAnExactPolynomialOfEveryOrder) {
  for (int order = 0; order <= 5; ++order) {
    SCOPED_TRACE(order);
    std::vector<double> truth(static_cast<std::size_t>(order) + 1);
    for (int i = 0; i <= order; ++i)
      truth[static_cast<std::size_t>(i)] = 0.3 * (i + 1) * (i % 2 ? -1 : 1);
    BiasPolynomial f{truth};
    std::vector<double> d, y;
    for (int i = 0; i < 40; ++i) {
      d.push_back(0.2 + 0.12 * i);
      y.push_back(f(d.back()));
    }
    const auto alpha = fitPolynomial(d, y, order);
    ASSERT_EQ(alpha.size(), truth.size());
    for (std::size_t i = 0; i < truth.size(); ++i) EXPECT_NEAR(alpha[i], truth[i], 1e-8);
  }
}

TEST(SelectOrder, AicOnAHandComputableCase) {
  // d = -3..3, y = d^2 + e with e orthogonal to 1, d, d^2, d^3. Then
  //   RSS_0 = RSS_1 = sum (d^2 - 4)^2 + |e|^2 = 84 + |e|^2   (d^2 - 4 is orthogonal to 1 and d)
  //   RSS_2 = RSS_3 = |e|^2
  // and AIC_n = 2 (n + 2) + N (ln(2 pi RSS_n / N) + 1).
  std::vector<double> d = {-3, -2, -1, 0, 1, 2, 3};
  std::vector<double> e = {3, -7, 1, 6, 1, -7, 3};  // degree-4 Gram polynomial on these points
  for (int k = 0; k <= 3; ++k) {
    double dot = 0;
    for (std::size_t i = 0; i < d.size(); ++i) dot += e[i] * std::pow(d[i], k);
    ASSERT_NEAR(dot, 0.0, 1e-12) << k;
  }
  const double scale = 0.01;
  std::vector<RangePair> pairs;
  double e2 = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    pairs.push_back({d[i], d[i] * d[i] + scale * e[i], 0});
    e2 += scale * scale * e[i] * e[i];
  }
  const auto sel = selectOrder(pairs, 3, OrderRule::aic);
  ASSERT_EQ(sel.table.size(), 4u);
  const double n = 7.0;
  const double rss[4] = {84 + e2, 84 + e2, e2, e2};
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    EXPECT_NEAR(sel.table[static_cast<std::size_t>(k)].rss_m2, rss[k], 1e-9);
    EXPECT_NEAR(sel.table[static_cast<std::size_t>(k)].aic,
                2.0 * (k + 2) + n * (kLog2Pi + std::log(rss[k] / n) + 1.0), 1e-6);
  }
  EXPECT_EQ(sel.order_aic, 2);
  EXPECT_EQ(sel.chosen, 2);
}

TEST(Alhashimi2016ClosedForm, MatchesItsFormulaOnATinyExample) {
  // Eqs. 24-26 with n = 1: H = [d^-2, d^-1], y~ = y / d^2, alpha = (H'H)^-1 H'y~,
  // sigma_e^2 = |y~ - H alpha|^2 / N, computed here by hand with a 2x2 inverse.
  const std::vector<double> d = {0.5, 1.0, 2.0, 4.0};
  const std::vector<double> y = {0.61, 1.02, 2.13, 4.05};
  double a11 = 0, a12 = 0, a22 = 0, b1 = 0, b2 = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double h1 = 1.0 / (d[i] * d[i]), h2 = 1.0 / d[i], t = y[i] / (d[i] * d[i]);
    a11 += h1 * h1;
    a12 += h1 * h2;
    a22 += h2 * h2;
    b1 += h1 * t;
    b2 += h2 * t;
  }
  const double det = a11 * a22 - a12 * a12;
  const double alpha0 = (a22 * b1 - a12 * b2) / det, alpha1 = (a11 * b2 - a12 * b1) / det;
  double s = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double r = y[i] / (d[i] * d[i]) - alpha0 / (d[i] * d[i]) - alpha1 / d[i];
    s += r * r;
  }
  const auto fit = fitAlhashimi2016ClosedForm(d, y, 1);
  ASSERT_EQ(fit.alpha.size(), 2u);
  EXPECT_NEAR(fit.alpha[0], alpha0, 1e-10);
  EXPECT_NEAR(fit.alpha[1], alpha1, 1e-10);
  EXPECT_NEAR(fit.sigma_e, std::sqrt(s / 4.0), 1e-12);
}

struct Draws {
  std::vector<double> d, y;
};

Draws drawAlhashimi2016(const RangeModel& m, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.3, 4.5);
  std::normal_distribution<double> g(0.0, 1.0);
  Draws out;
  for (int i = 0; i < n; ++i) {
    const double d = u(rng);
    out.d.push_back(d);
    out.y.push_back(m.bias(d) + m.noise.stddev(d, m.bias) * g(rng));
  }
  return out;
}

TEST(Alhashimi2016ML, RecoversTheModelAndImprovesOnTheClosedFormLikelihood) {
  RangeModel m;
  m.bias.alpha = {0.0525, 0.8838, 0.0584};
  m.noise.kind = NoiseKind::squared;
  m.noise.sigma_e = 0.004;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    const auto draws = drawAlhashimi2016(m, 3000, seed);
    const auto cf = fitAlhashimi2016ClosedForm(draws.d, draws.y, 2);
    const auto ml = fitAlhashimi2016ML(draws.d, draws.y, cf.alpha);
    // ML maximises the likelihood of model (1): never worse than its start.
    EXPECT_LE(ml.neg_log_likelihood, cf.neg_log_likelihood + 1e-9);
    EXPECT_NEAR(ml.sigma_e, m.noise.sigma_e, 0.1 * m.noise.sigma_e);
    for (double dist : {0.5, 2.0, 4.0})
      EXPECT_NEAR(BiasPolynomial{ml.alpha}(dist), m.bias(dist), 0.01);
  }
}

TEST(NoisePolynomial, RecoversThePolynomialNoiseOfAlhashimi2021) {
  RangeModel m;
  m.bias.alpha = {0.0525, 0.8838, 0.0584};
  m.noise.kind = NoiseKind::polynomial;
  m.noise.beta = {0.01, 0.02};  // sigma(d) = 0.01 + 0.02 d
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    const auto draws = drawAlhashimi2016(m, 5000, seed);
    std::vector<double> r(draws.d.size());
    for (std::size_t i = 0; i < r.size(); ++i) r[i] = draws.y[i] - m.bias(draws.d[i]);
    const auto beta = fitNoisePolynomial(draws.d, r, 1);
    for (double dist : {0.5, 2.0, 4.0})
      EXPECT_NEAR(std::abs(beta[0] + beta[1] * dist), 0.01 + 0.02 * dist, 0.005);
  }
}

class NoiseExponent : public ::testing::TestWithParam<int> {};

TEST_P(NoiseExponent, PicksTheExponentTheDataWereDrawnWith) {
  const int k = GetParam();
  BiasPolynomial f{{0.0525, 0.8838, 0.0584}};
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<std::vector<double>> batches;
    for (int b = 0; b < 60; ++b) {  // distances 0.3 .. 4.4 m, 10 repeated readings each
      const double fd = f(0.3 + 0.07 * b);
      std::vector<double> y;
      for (int i = 0; i < 10; ++i) y.push_back(fd + 0.005 * std::pow(fd, k) * g(rng));
      batches.push_back(y);
    }
    const auto t = testNoiseExponent(batches);
    EXPECT_EQ(t.batches, 60u);
    EXPECT_EQ(t.best, k);
  }
}

INSTANTIATE_TEST_SUITE_P(H0toH3, NoiseExponent, ::testing::Values(0, 1, 2, 3));

}  // namespace
}  // namespace lidarcal::calibration
