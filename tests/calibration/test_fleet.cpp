// SPDX-License-Identifier: BSD-3-Clause
// Fleet statistics (pipeline/fleet.hpp) on models written here with a known covariance: the bias
// and its standard error against a hand computation, Wald's test against its closed form for one
// distance, the false-alarm rate over many simulated fleets of unchanged sensors held to alpha,
// a 2 cm offset found in a fleet of 21, and the cases that cannot be tested or are refused.

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "calibration/fleet.hpp"
#include "common/errors.hpp"
#include "common/rng.hpp"

namespace lidarcal::calibration {
namespace {

/// The simulated sensors' bias (the paper field's, Alhashimi et al. 2021 section 4.1 values).
const std::vector<double> kTrueAlpha = {0.0525, 0.8838, 0.0584};

/// A covariance of alpha like a small calibration's: standard errors 1.5 mm, 3.7 mm/m, 0.6 mm/m^2,
/// alpha_0 and alpha_1 anticorrelated.
Eigen::Matrix3d typicalCovariance() {
  const Eigen::Vector3d se(0.0015, 0.0037, 0.0006);
  Eigen::Matrix3d corr;
  corr << 1.0, -0.8, 0.6, -0.8, 1.0, -0.9, 0.6, -0.9, 1.0;
  return se.asDiagonal() * corr * se.asDiagonal();
}

/// A calibration of a sensor whose true coefficients are `truth`: alpha drawn from N(truth, Sigma)
/// (what a calibration with that covariance reports), fitted over 0.6-4.1 m.
FleetEntry calibration(const std::string& sensor, const std::string& date,
                       std::vector<double> truth, std::mt19937_64& rng) {
  const Eigen::Matrix3d sigma = typicalCovariance();
  const Eigen::Matrix3d L = sigma.llt().matrixL();
  std::normal_distribution<double> n01;
  const Eigen::Vector3d draw = L * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
  FleetEntry e;
  e.sensor = sensor;
  e.date = date;
  e.source = sensor + "/" + date + "/model.json";
  for (int i = 0; i < 3; ++i) truth[static_cast<std::size_t>(i)] += draw(i);
  e.model.model.bias.alpha = truth;
  e.model.model.noise.kind = NoiseKind::squared;
  e.model.model.noise.sigma_e = 0.0019;
  // symmetric: storage order does not matter
  e.model.alpha_covariance.assign(sigma.data(), sigma.data() + 9);
  e.model.fitted_range_m = std::make_pair(0.6, 4.1);
  e.model.method = "joint";
  return e;
}

/// A fleet of `sensors` calibrated twice; sensor `moved` (if any) has alpha_0 + offset the second
/// time.
std::vector<FleetEntry> fleet(std::uint64_t seed, int sensors, int moved = -1,
                              double offset_m = 0.02) {
  std::mt19937_64 rng = makeRng(seed, 0);
  std::vector<FleetEntry> out;
  for (int i = 0; i < sensors; ++i) {
    const std::string name = "robot" + std::to_string(100 + i);
    out.push_back(calibration(name, "2024-03-04", kTrueAlpha, rng));
    std::vector<double> now = kTrueAlpha;
    if (i == moved) now[0] += offset_m;
    out.push_back(calibration(name, "2024-03-11", now, rng));
  }
  return out;
}

TEST(FleetStatistics, BiasAndItsStandardErrorFollowTheCovariance) {
  CalibrationModel m;
  m.model.bias.alpha = {0.01, 1.02};
  m.alpha_covariance = {4e-6, -1e-6, -1e-6, 9e-6};  // var a0, cov, cov, var a1
  m.fitted_range_m = std::make_pair(0.5, 2.5);
  const auto b = biasAt(m, {1.0, 2.0, 3.0});
  ASSERT_EQ(b.size(), 3u);
  EXPECT_NEAR(b[1].bias_m, 0.01 + 1.02 * 2.0 - 2.0, 1e-15);
  // var(a0 + a1 d) = 4e-6 + 2 d (-1e-6) + d^2 9e-6
  EXPECT_NEAR(b[1].se_m, std::sqrt(4e-6 - 4e-6 + 36e-6), 1e-15);
  EXPECT_TRUE(b[0].inside);
  EXPECT_FALSE(b[2].inside);  // beyond the fitted range
  m.alpha_covariance.clear();
  EXPECT_TRUE(std::isnan(biasAt(m, {1.0})[0].se_m));
}

TEST(FleetStatistics, MovedAtOneDistanceIsTheSquaredChangeOverBothVariances) {
  std::mt19937_64 rng = makeRng(3, 0);
  std::vector<FleetEntry> two = {calibration("a", "2024-01-01", kTrueAlpha, rng),
                                 calibration("a", "2024-02-01", kTrueAlpha, rng)};
  two[1].model.model.bias.alpha[0] += 0.004;
  FleetConfig config;
  config.distances_m = {2.0};
  const FleetSummary s = summarizeFleet(two, config);
  ASSERT_EQ(s.rows.size(), 1u);
  const FleetTest& t = s.rows[0].moved;
  ASSERT_TRUE(t.tested) << t.why_not;
  const auto now = biasAt(two[1].model, {2.0})[0], before = biasAt(two[0].model, {2.0})[0];
  const double var = now.se_m * now.se_m + before.se_m * before.se_m;
  const double w = std::pow(now.bias_m - before.bias_m, 2) / var;
  EXPECT_EQ(t.dof, 1);
  EXPECT_NEAR(t.statistic, w, 1e-9 * w);
  EXPECT_NEAR(t.p, std::erfc(std::sqrt(w / 2.0)), 1e-9);  // chi-square with 1 degree of freedom
  EXPECT_EQ(t.p_holm, t.p);                               // one test: Holm changes nothing
  EXPECT_FALSE(s.rows[0].outlier.tested);                 // no fleet to compare with
}

TEST(FleetStatistics, UnchangedFleetsRaiseFewFalseAlarms) {
  // 200 fleets of 20 unchanged sensors: each family is held to alpha = 0.01 over the fleet, so
  // about 2 % of the fleets may show a flag; 10 of 200 would be a miscalibrated test.
  int fleets_with_a_flag = 0;
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    const FleetSummary s = summarizeFleet(fleet(seed, 20), FleetConfig{});
    if (!s.flagged.empty()) ++fleets_with_a_flag;
  }
  EXPECT_LE(fleets_with_a_flag, 10);
}

TEST(FleetStatistics, ATwoCentimetreOffsetAmongTwentyUnchangedSensorsIsFlagged) {
  // In every one of 20 fleets the moved sensor is flagged, on both tests; a false alarm on one of
  // the 20 others may happen in about 2 % of the fleets (alpha per family), so at most 3 of 20.
  int fleets_with_a_false_alarm = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE(seed);
    const FleetSummary s = summarizeFleet(fleet(seed, 21, 7), FleetConfig{});
    ASSERT_EQ(s.rows.size(), 21u);
    const FleetRow& r = s.rows[7];
    ASSERT_EQ(r.current.sensor, "robot107");
    EXPECT_TRUE(r.moved.flagged);
    EXPECT_TRUE(r.outlier.flagged);
    if (s.flagged != std::vector<std::string>{"robot107"}) ++fleets_with_a_false_alarm;
    // The change it reports is the 2 cm shift within 5 standard errors of the difference.
    for (std::size_t j = 0; j < r.moved.distances_m.size(); ++j) {
      const double se = std::hypot(r.bias[j].se_m, r.previous_bias[j].se_m);
      EXPECT_NEAR(r.moved.difference_m[j], 0.02, 5.0 * se);
    }
  }
  EXPECT_LE(fleets_with_a_false_alarm, 3);
}

TEST(FleetStatistics, WhatCannotBeTestedSaysWhy) {
  std::vector<FleetEntry> entries = fleet(5, 4);
  entries[1].model.alpha_covariance.clear();  // robot100's latest without standard errors
  // robot101's latest far from the others
  entries[3].model.fitted_range_m = std::make_pair(5.0, 6.0);
  const FleetSummary s = summarizeFleet(entries, FleetConfig{});
  ASSERT_EQ(s.rows.size(), 4u);
  EXPECT_FALSE(s.rows[0].moved.tested);
  EXPECT_NE(s.rows[0].moved.why_not.find("alpha_covariance"), std::string::npos);
  EXPECT_FALSE(s.rows[1].moved.tested);
  EXPECT_NE(s.rows[1].moved.why_not.find("fitted ranges"), std::string::npos);
  EXPECT_TRUE(s.rows[2].moved.tested);
  // Four sensors: fewer than five others for any fleet comparison.
  for (const FleetRow& r : s.rows) EXPECT_FALSE(r.outlier.tested);
  EXPECT_NE(s.rows[2].outlier.why_not.find("fewer than 5"), std::string::npos);
  EXPECT_TRUE(s.flagged.empty());
}

TEST(FleetStatistics, AmbiguousHistoriesAreRefused) {
  std::vector<FleetEntry> entries = fleet(6, 2);
  entries[1].date = entries[0].date;  // robot100 twice on one date
  EXPECT_THROW(summarizeFleet(entries, FleetConfig{}), InputError);
  entries[1].date = "";  // one calibration without a date beside another
  EXPECT_THROW(summarizeFleet(entries, FleetConfig{}), InputError);
  FleetConfig bad;
  bad.distances_m = {2.0, 1.0};
  EXPECT_THROW(summarizeFleet(fleet(6, 2), bad), std::invalid_argument);
}

}  // namespace
}  // namespace lidarcal::calibration
