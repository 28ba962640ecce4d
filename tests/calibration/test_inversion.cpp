// Inversion of the bias (seed 004 section 5.2): LS round trip f(f^-1(y)) = y over the range
// limits for every order, and ML satisfying eq. 28.

#include <cmath>

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
                         ::testing::Values(Case{"order1", {0.05, 1.1}}, Case{"order2", {0.0525, 0.8838, 0.0584}},
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
  BiasPolynomial dip{{0.0, 1.0, -0.5, 0.06}};  // f' = 1 - d + 0.18 d^2 < 0 on (1.31, 4.25), where f is ~0.6
  EXPECT_FALSE(invertsReadingWindow(dip, 0.2, 6.0, &where));
  EXPECT_NEAR(where, (1.0 - std::sqrt(0.28)) / 0.36, 1e-9);
}

TEST(Inversion, OrderZeroCannotBeInverted) {
  RangeModel m;
  m.bias.alpha = {1.0};
  EXPECT_THROW(RangeInverter(m, InversionConfig{}), std::invalid_argument);
}

}  // namespace
}  // namespace lidarcal::calibration
