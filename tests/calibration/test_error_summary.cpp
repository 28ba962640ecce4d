// SPDX-License-Identifier: BSD-3-Clause
// The RMS error against a reference with its standard error, and the MSE ratio with its
// interval (calibration/error_summary.hpp): the intervals hold the truth the test draws from.

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "calibration/error_summary.hpp"

namespace lidarcal::calibration {
namespace {

TEST(ErrorSummary, TheRmsStandardErrorIsTheSpreadOfTheRmsOverRecordings) {
  // Errors of 20 entries drawn with a true RMS of 4 mm, many times: the standard error the
  // summary states is, on average, the spread of the RMS between those draws.
  std::mt19937_64 rng(21);
  std::normal_distribution<double> error(0.001, std::sqrt(0.004 * 0.004 - 0.001 * 0.001));
  const int trials = 4000;
  double sum = 0.0, sum2 = 0.0, se2 = 0.0;
  for (int t = 0; t < trials; ++t) {
    std::vector<double> e(20);
    for (double& v : e) v = error(rng);
    const RmsError r = rmsError(e);
    ASSERT_EQ(r.entries, 20u);
    sum += r.rms_m, sum2 += r.rms_m * r.rms_m, se2 += r.se_m * r.se_m;
  }
  const double spread = std::sqrt(sum2 / trials - std::pow(sum / trials, 2)),
               stated = std::sqrt(se2 / trials);
  EXPECT_NEAR(stated / spread, 1.0, 0.1);
  EXPECT_NEAR(sum / trials, 0.004, 0.0002);  // the RMS itself is nearly unbiased
}

TEST(ErrorSummary, TheMseRatiosIntervalHoldsTheTrueRatioWhetherOrNotTheErrorsArePaired) {
  // Raw errors with twice the corrected ones' spread: the true ratio is 4. Unpaired (independent)
  // and paired (the corrected error a share of the raw one plus its own), 30 entries each.
  std::mt19937_64 rng(22);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int trials = 2000;
  double log_width[2] = {0.0, 0.0};  // mean ln(high / low): independent, paired
  for (const bool paired : {false, true}) {
    SCOPED_TRACE(paired ? "paired" : "independent");
    int inside = 0;
    for (int t = 0; t < trials; ++t) {
      std::vector<double> raw(30), cor(30);
      for (std::size_t g = 0; g < raw.size(); ++g) {
        raw[g] = 0.004 * normal(rng);
        // paired: 0.4 raw + an independent part, so that var(cor) = 0.16 + 0.09 = 0.25 var(raw)
        cor[g] = paired ? 0.4 * raw[g] + 0.0012 * normal(rng) : 0.002 * normal(rng);
      }
      const MseRatio q = mseRatio(raw, cor);
      ASSERT_EQ(q.entries, 30u);
      inside += q.low <= 4.0 && 4.0 <= q.high;
      log_width[paired] += std::log(q.high / q.low) / trials;
    }
    EXPECT_GE(inside, trials * 90 / 100);
    EXPECT_LE(inside, trials * 97 / 100);
  }
  // Pairing takes the entries' shared part out: the interval narrows (here from x4.2 to x2.4).
  EXPECT_LT(log_width[1], 0.75 * log_width[0]);
}

TEST(ErrorSummary, TooFewEntriesGiveNoIntervalAndAPerfectCorrectionNoRatio) {
  EXPECT_TRUE(std::isnan(rmsError({}).rms_m));
  const RmsError one = rmsError({0.003});
  EXPECT_DOUBLE_EQ(one.rms_m, 0.003);
  EXPECT_TRUE(std::isnan(one.se_m));
  const MseRatio single = mseRatio({0.004}, {0.002});
  EXPECT_DOUBLE_EQ(single.ratio, 4.0);
  EXPECT_TRUE(std::isnan(single.low));
  EXPECT_TRUE(std::isnan(mseRatio({0.004, 0.001}, {0.0, 0.0}).ratio));
  EXPECT_THROW(mseRatio({0.004}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace lidarcal::calibration
