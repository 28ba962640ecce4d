// SPDX-License-Identifier: BSD-3-Clause
// The correction rule (calibration/filtering.hpp): what happens to a reading inside and beyond
// the range a model was fitted over, under every --outside policy, and its standard error.

#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "calibration/filtering.hpp"

namespace lidarcal::calibration {
namespace {

/// The simulated triangulation lidar of Alhashimi et al. 2021 (alpha = 0.0525, 0.8838,
/// 0.0584), fitted over true distances 1-4 m, with a covariance of its coefficients.
CalibrationModel quadraticModel() {
  CalibrationModel m;
  m.method = "joint";
  m.model.bias.alpha = {0.0525, 0.8838, 0.0584};
  m.model.range_min_m = 0.2;
  m.model.range_max_m = 12.0;
  m.fitted_range_m = std::make_pair(1.0, 4.0);
  m.alpha_covariance = {1e-6,  -2e-7, 1e-8,   //
                        -2e-7, 1e-6,  -1e-7,  //
                        1e-8,  -1e-7, 1e-7};
  return m;
}

TEST(Filtering, LinearContinuationJoinsTheFitWithoutAStepOrAKink) {
  const CalibrationModel m = quadraticModel();
  const ReadingCorrector correct = readingCorrector(m, InversionMethod::ls, Outside::linear);
  for (const double edge_d : {1.0, 4.0}) {
    SCOPED_TRACE(edge_d);
    const double edge_y = m.model.bias(edge_d);
    const double h = 1e-5;
    const CorrectedReading in_a = correct(edge_y - (edge_d > 2 ? 2 * h : -2 * h));
    const CorrectedReading in_b = correct(edge_y - (edge_d > 2 ? h : -h));
    const CorrectedReading out_a = correct(edge_y + (edge_d > 2 ? h : -h));
    const CorrectedReading out_b = correct(edge_y + (edge_d > 2 ? 2 * h : -2 * h));
    EXPECT_EQ(in_b.fate, ReadingFate::corrected);
    EXPECT_EQ(out_a.fate, ReadingFate::extrapolated);
    // No step: the corrected distances on either side of the edge differ by the reading step
    // over the slope; no kink: the slopes on either side agree.
    const double slope_in = (in_b.range_m - in_a.range_m) / h,
                 slope_out = (out_b.range_m - out_a.range_m) / h;
    EXPECT_NEAR(out_a.range_m - in_b.range_m,
                2 * h / m.model.bias.derivative(edge_d) * (edge_d > 2 ? 1 : -1), 1e-9);
    EXPECT_NEAR(slope_out, slope_in, 1e-4 * std::abs(slope_in));
  }
}

TEST(Filtering, BeyondTheEdgeTheCorrectionFollowsTheTangentNotThePolynomial) {
  const CalibrationModel m = quadraticModel();
  const ReadingCorrector linear = readingCorrector(m, InversionMethod::ls, Outside::linear);
  const ReadingCorrector poly = readingCorrector(m, InversionMethod::ls, Outside::extrapolate);
  const double y = 9.0;  // well above f(4) = 4.52
  const double tangent = 4.0 + (y - m.model.bias(4.0)) / m.model.bias.derivative(4.0);
  EXPECT_NEAR(linear(y).range_m, tangent, 1e-12);
  EXPECT_NEAR(m.model.bias(poly(y).range_m), y, 1e-9);  // the polynomial's own root
  EXPECT_EQ(poly(y).fate, ReadingFate::extrapolated);
  // Inside the fitted range every policy gives the same distance, bit for bit.
  for (const Outside o : {Outside::linear, Outside::keep, Outside::extrapolate, Outside::drop}) {
    const CorrectedReading c = readingCorrector(m, InversionMethod::ls, o)(3.0);
    EXPECT_EQ(c.fate, ReadingFate::corrected);
    EXPECT_EQ(c.range_m, linear(3.0).range_m);
  }
}

TEST(Filtering, KeepAndDropLeaveReadingsBeyondTheEdgeUncorrected) {
  const CalibrationModel m = quadraticModel();
  const CorrectedReading kept = readingCorrector(m, InversionMethod::ls, Outside::keep)(7.0);
  EXPECT_EQ(kept.fate, ReadingFate::outside_kept);
  EXPECT_EQ(kept.range_m, 7.0);
  EXPECT_TRUE(std::isnan(kept.standard_error_m));
  const CorrectedReading dropped = readingCorrector(m, InversionMethod::ls, Outside::drop)(0.5);
  EXPECT_EQ(dropped.fate, ReadingFate::outside_dropped);
  EXPECT_TRUE(std::isnan(dropped.range_m));
}

TEST(Filtering, TheStandardErrorIsTheDeltaMethodsAndGrowsPastTheEdge) {
  const CalibrationModel m = quadraticModel();
  const ReadingCorrector correct = readingCorrector(m, InversionMethod::ls, Outside::linear);
  // Inside: var f(d) = x' C x with x = (1, d, d^2), divided by f'(d)^2.
  const double d = 2.5, y = m.model.bias(d);
  const double x[3] = {1.0, d, d * d};
  double v = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      v += x[i] * m.alpha_covariance[static_cast<std::size_t>(3 * i + j)] * x[j];
  EXPECT_NEAR(correct(y).standard_error_m, std::sqrt(v) / m.model.bias.derivative(d), 1e-12);
  // Beyond: continuous at the edge, then growing with the distance past it.
  const double at_edge = correct(m.model.bias(4.0)).standard_error_m;
  double previous = at_edge;
  for (const double reading : {4.6, 5.5, 7.0, 9.0}) {
    const CorrectedReading c = correct(reading);
    ASSERT_EQ(c.fate, ReadingFate::extrapolated);
    EXPECT_GT(c.standard_error_m, previous);
    previous = c.standard_error_m;
  }
  EXPECT_NEAR(correct(m.model.bias(4.0) + 1e-9).standard_error_m, at_edge, 1e-9);
  // Without a covariance there is no standard error to give.
  CalibrationModel bare = m;
  bare.alpha_covariance.clear();
  EXPECT_TRUE(std::isnan(
      readingCorrector(bare, InversionMethod::ls, Outside::linear)(3.0).standard_error_m));
}

TEST(Filtering, ThePredictiveStandardErrorAddsTheDiscrepancyThroughTheSlope) {
  CalibrationModel m = quadraticModel();
  const ReadingCorrector curve_only = readingCorrector(m, InversionMethod::ls, Outside::linear);
  m.discrepancy.method = "reml";
  m.discrepancy.sigma_m = 0.004;
  m.discrepancy.dof = 12;
  const ReadingCorrector correct = readingCorrector(m, InversionMethod::ls, Outside::linear);
  // Inside (2.5 m) and beyond the edge (a reading continued past 4 m): the curve's standard error
  // is what it was, and the predictive one adds the discrepancy, in distance units through the
  // slope of the rule that corrected the reading (f' at d inside, at the edge beyond).
  for (const double reading : {m.model.bias(2.5), 6.0}) {
    SCOPED_TRACE(reading);
    const CorrectedReading before = curve_only(reading), c = correct(reading);
    EXPECT_DOUBLE_EQ(c.range_m, before.range_m);
    EXPECT_DOUBLE_EQ(c.curve_standard_error_m, before.standard_error_m);
    // no discrepancy: the curve's
    EXPECT_DOUBLE_EQ(before.standard_error_m, before.curve_standard_error_m);
    const double slope = m.model.bias.derivative(std::min(c.range_m, 4.0));
    const double expected = std::hypot(c.curve_standard_error_m, 0.004 / slope);
    EXPECT_NEAR(c.standard_error_m, expected, 1e-12);
    const CorrectionErrors at = correct.errorsAt(c.range_m);
    EXPECT_DOUBLE_EQ(at.predictive_m, c.standard_error_m);
    EXPECT_DOUBLE_EQ(at.curve_m, c.curve_standard_error_m);
  }
}

TEST(Filtering, AReadingContinuedBelowZeroDistanceHasNone) {
  const CalibrationModel m = quadraticModel();
  const CorrectedReading c = readingCorrector(m, InversionMethod::ls, Outside::linear)(0.01);
  // f(1) = 0.9947, f'(1) = 1.0006: the tangent reaches d = 0 at a reading of about -0.006 m, so
  // 0.01 m lies just above it and still has a distance; a reading of 0 or less has none.
  EXPECT_EQ(c.fate, ReadingFate::extrapolated);
  EXPECT_GT(c.range_m, 0.0);
  EXPECT_EQ(readingCorrector(m, InversionMethod::ls, Outside::linear)(0.0).fate,
            ReadingFate::unresolved);
}

TEST(Filtering, CorrectedScansMarkEveryPointAndCountTheReadingsBeyond) {
  const CalibrationModel m = quadraticModel();
  io::Scan scan;
  scan.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const float r : {0.5f, 2.0f, nan, 8.0f}) {
    pcl::PointXYZI p;
    p.x = r;
    p.y = 0.0f;
    p.z = std::isnan(r) ? nan : 0.0f;
    scan.cloud->push_back(p);
  }
  FilteringStats stats;
  const io::Scan linear =
      correctScan(scan, readingCorrector(m, InversionMethod::ls, Outside::linear), &stats);
  ASSERT_EQ(linear.correction.size(), 4u);
  EXPECT_EQ(linear.correction[0], io::PointCorrection::extrapolated);
  EXPECT_EQ(linear.correction[1], io::PointCorrection::corrected);
  EXPECT_EQ(linear.correction[2], io::PointCorrection::no_return);
  EXPECT_EQ(linear.correction[3], io::PointCorrection::extrapolated);
  EXPECT_EQ(stats.corrected, 1u);
  EXPECT_EQ(stats.extrapolated, 2u);
  EXPECT_EQ(stats.below, 1u);
  EXPECT_EQ(stats.beyond_min_m, 0.5);
  EXPECT_EQ(stats.beyond_max_m, 8.0);
  EXPECT_TRUE(std::isfinite(linear.correction_se[3]));
  const io::Scan kept =
      correctScan(scan, readingCorrector(m, InversionMethod::ls, Outside::keep), &stats);
  EXPECT_EQ(kept.correction[3], io::PointCorrection::raw);
  EXPECT_EQ((*kept.cloud)[3].x, 8.0f);
  EXPECT_EQ(stats.outside, 2u);
  EXPECT_EQ((*scan.cloud)[3].x, 8.0f);  // the input is not modified
}

TEST(Filtering, PolicyNamesRoundTrip) {
  for (const std::string& name : outsidePolicies()) {
    Outside o = Outside::drop;
    ASSERT_TRUE(parseOutside(name, o));
    EXPECT_EQ(name, toString(o));
  }
  Outside o = Outside::keep;
  EXPECT_FALSE(parseOutside("nearest", o));
  EXPECT_EQ(outsidePolicies().front(), toString(kDefaultOutside));
}

}  // namespace
}  // namespace lidarcal::calibration
