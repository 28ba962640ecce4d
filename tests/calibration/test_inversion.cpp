// SPDX-License-Identifier: BSD-3-Clause
// Inversion of the bias (Alhashimi et al. 2016 section 5.2): LS round trip f(f^-1(y)) = y over the
// range limits for every order, and ML satisfying eq. 28.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "calibration/inversion.hpp"

namespace lidarcal::calibration {
namespace {

struct Case {
  const char* name;
  std::vector<double> alpha;
};

class InversionRoundTrip : public ::testing::TestWithParam<Case> {};

TEST_P(InversionRoundTrip, FOfTheInverseIsTheReadingOverTheRangeLimits) {
  RangeModel m;
  m.bias.alpha = GetParam().alpha;
  m.range_min_m = 0.2;
  m.range_max_m = 6.0;
  ASSERT_TRUE(isMonotone(m.bias, 0.1, 6.0));
  InversionConfig c;
  c.d_max_m = 10.0;
  RangeInverter inv(m, c);
  for (double y = m.range_min_m; y <= m.range_max_m; y += 0.01) {
    const auto d = inv.invert(y);
    ASSERT_TRUE(d) << y;
    EXPECT_NEAR(m.bias(*d), y, 1e-9) << y;
  }
}

INSTANTIATE_TEST_SUITE_P(Orders, InversionRoundTrip,
                         ::testing::Values(Case{"order1", {0.05, 1.1}},
                                           Case{"order2", {0.0525, 0.8838, 0.0584}},
                                           Case{"order3", {0.02, 0.95, 0.03, 0.004}},
                                           Case{"order4", {0.01, 0.9, 0.05, 0.002, 0.0003}}),
                         [](const auto& p) { return std::string(p.param.name); });

TEST(Inversion, MlSatisfiesEq28AndTendsToLsForSmallNoise) {
  RangeModel m;
  m.bias.alpha = {0.0525, 0.8838, 0.0584};
  m.noise.kind = NoiseKind::squared;
  m.noise.sigma_e = 0.01;
  InversionConfig ml;
  ml.method = InversionMethod::ml;
  ml.d_max_m = 10.0;
  RangeInverter inv(m, ml);
  for (double y = 0.3; y < 6.0; y += 0.1) {
    const auto d = inv.invert(y);
    ASSERT_TRUE(d);
    const double f = m.bias(*d), df = m.bias.derivative(*d);
    // (y - f)(y - f + d f'/2) = sigma_e^2 d^4
    EXPECT_NEAR((y - f) * (y - f + 0.5 * *d * df), 0.0001 * std::pow(*d, 4), 1e-9) << y;
  }
  m.noise.sigma_e = 1e-7;
  RangeInverter tiny(m, ml);
  InversionConfig ls;
  ls.d_max_m = 10.0;
  RangeInverter lsinv(m, ls);
  for (double y = 0.3; y < 6.0; y += 0.25) EXPECT_NEAR(*tiny.invert(y), *lsinv.invert(y), 1e-6);
}

TEST(Inversion, NonMonotonePolynomialIsDetectedAndNaNStaysNaN) {
  BiasPolynomial f{{0.0, 2.0, -0.5}};  // peaks at d = 2
  double where = 0;
  EXPECT_FALSE(isMonotone(f, 0.2, 6.0, &where));
  EXPECT_NEAR(where, 2.0, 1e-9);
  RangeModel m;
  m.bias.alpha = {0.0, 1.0};
  RangeInverter inv(m, InversionConfig{});
  EXPECT_FALSE(inv.invert(std::nan("")));
}

TEST(Inversion, ReadingWindowIsCheckedOnlyWhereReadingsCanFall) {
  // f rises to 6.0 at d = 4 and falls after d = 5: every reading in [0.2, 6] has one distance.
  BiasPolynomial peaked{{0.0, 2.5, -0.25}};  // f(4) = 6, peak f(5) = 6.25
  EXPECT_TRUE(invertsReadingWindow(peaked, 0.2, 6.0));
  double where = 0;
  EXPECT_FALSE(invertsReadingWindow(peaked, 0.2, 6.5, &where));  // 6.25 is the most it reads
  // f' = 1 - d + 0.18 d^2 < 0 on (1.31, 4.25), where f is ~0.6
  BiasPolynomial dip{{0.0, 1.0, -0.5, 0.06}};
  EXPECT_FALSE(invertsReadingWindow(dip, 0.2, 6.0, &where));
  EXPECT_NEAR(where, (1.0 - std::sqrt(0.28)) / 0.36, 1e-9);
}

// Brute force, independent of the inverter's root search: every sign change of f(d) - y on a
// 0.1 mm grid, bisected to 1e-12 m; and the likelihood of model (21) maximised on the grid.
std::vector<double> gridRoots(const BiasPolynomial& f, double y, double lo, double hi) {
  std::vector<double> roots;
  const double step = 1e-4;
  for (double a = lo; a < hi; a += step) {
    double b = std::min(a + step, hi), fa = f(a) - y;
    if (fa == 0.0) roots.push_back(a);
    if ((fa < 0.0) == (f(b) - y < 0.0)) continue;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (a + b);
      ((f(mid) - y < 0.0) == (fa < 0.0) ? a : b) = mid;
    }
    roots.push_back(a);
  }
  return roots;
}

TEST(Inversion, LsTakesTheRootNearestTheReadingAmongAllRootsInTheWindow) {
  // Non-monotone polynomials with one to three distances per reading inside [0, 8] m.
  const std::vector<std::vector<double>> models = {{0.0, 1.0, -0.5, 0.06},
                                                   {0.05, 2.5, -0.25},
                                                   {0.02, 0.95, 0.03, 0.004},
                                                   {-0.1, 1.6, -0.5, 0.04, 0.0006}};
  for (const auto& alpha : models) {
    RangeModel m;
    m.bias.alpha = alpha;
    InversionConfig c;
    c.d_max_m = 8.0;
    const RangeInverter inv(m, c);
    int multiple = 0;  // readings with more than one distance in the window
    for (double y = 0.05; y < 7.0; y += 0.0137) {
      const std::vector<double> roots = gridRoots(m.bias, y, 0.0, 8.0);
      multiple += roots.size() > 1;
      const auto d = inv.invert(y);
      ASSERT_EQ(d.has_value(), !roots.empty()) << "y = " << y;
      if (!d) continue;
      const double nearest = *std::min_element(roots.begin(), roots.end(), [&](double a, double b) {
        return std::abs(a - y) < std::abs(b - y);
      });
      EXPECT_NEAR(*d, nearest, 1e-9) << "y = " << y;
      EXPECT_NEAR(m.bias(*d), y, 1e-12 * std::max(1.0, std::abs(y)))
          << "to machine precision, y = " << y;
    }
    if (alpha[2] < 0.0) {
      EXPECT_GT(multiple, 10) << "a falling part must give readings several distances (model "
                              << &alpha - models.data() << ")";
    }
  }
}

TEST(Inversion, MlTakesTheMostLikelyDistanceInTheWindow) {
  // The answer must be the likelihood's maximum on a 0.1 mm grid (or better), also where the
  // noise is large enough for distant stationary points to matter, and where f - 4 =
  // (d - 2)(d - 4)(d - 6) / 2 gives readings near 4 m three distances: the likelihood then
  // prefers the nearest (about 2 m), while LS takes the one nearest the reading (about 4 m).
  for (const double sigma_e : {0.002, 0.02, 0.1}) {
    for (const auto& alpha : std::vector<std::vector<double>>{
             {0.03, 0.98, 0.004, -0.0001}, {0.0525, 0.8838, 0.0584}, {-20.0, 22.0, -6.0, 0.5}}) {
      RangeModel m;
      m.bias.alpha = alpha;
      m.noise.kind = NoiseKind::squared;
      m.noise.sigma_e = sigma_e;
      InversionConfig c;
      c.method = InversionMethod::ml;
      c.d_max_m = 12.0;
      const RangeInverter inv(m, c);
      const double s2 = sigma_e * sigma_e;
      for (double y = 0.2; y < 9.0; y += 0.173) {
        auto loglik = [&](double d) {
          const double r = y - m.bias(d);
          return -std::log(d * d) - r * r / (2.0 * s2 * std::pow(d, 4));
        };
        double grid_best = -1e300;
        for (double d = 1e-4; d <= 12.0; d += 1e-4) grid_best = std::max(grid_best, loglik(d));
        const auto d = inv.invert(y);
        ASSERT_TRUE(d) << "y = " << y;
        EXPECT_GE(loglik(*d), grid_best - 1e-9) << "sigma_e " << sigma_e << ", y = " << y;
      }
    }
  }
}

TEST(Inversion, OrderZeroCannotBeInverted) {
  RangeModel m;
  m.bias.alpha = {1.0};
  EXPECT_THROW(RangeInverter(m, InversionConfig{}), std::invalid_argument);
  m.bias.alpha.assign(11, 0.1);  // order 10: above model.json's limit
  EXPECT_THROW(RangeInverter(m, InversionConfig{}), std::invalid_argument);
}

}  // namespace
}  // namespace lidarcal::calibration
