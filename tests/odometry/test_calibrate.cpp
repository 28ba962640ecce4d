// SPDX-License-Identifier: BSD-3-Clause
// The whole calibration: recovery with injected scan-matching failures, its bookkeeping, clean
// statuses on degenerate drives, and the published results of Censi et al. 2013 on the shared
// recordings (configurations B and C, skipped when ../shared/data is absent).

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/odometry_tuples.hpp"
#include "odometry/calibrate.hpp"
#include "odometry/simulated_samples.hpp"
#include "test_util.hpp"

namespace lidarcal::odometry {
namespace {

TEST(Calibrate, RecoversTheTruthThroughScanMatchingFailures) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE(seed);
    SimulationSettings settings;
    settings.samples = 2000;
    settings.outlier_fraction = 0.03;
    settings.seed = seed;
    const OdometryResult r = calibrateOdometry(simulateSamples(settings));
    ASSERT_TRUE(r.ok()) << r.status.message;
    const Vector6 z = (r.estimate.toVector() - settings.truth.toVector())
                          .cwiseAbs()
                          .cwiseQuotient(r.standardErrors());
    EXPECT_LT(z.maxCoeff(), 4.0) << z.transpose();
  }
}

TEST(Calibrate, WithoutTrimmingTheFailuresPullTheEstimateAway) {
  // The same drive untrimmed: the failures bias the estimate by many (honest) standard errors
  // of the trimmed one; the trimming is what makes the method usable on real scan matching.
  SimulationSettings settings;
  settings.samples = 2000;
  settings.outlier_fraction = 0.05;
  const std::vector<OdometrySample> samples = simulateSamples(settings);
  OdometrySettings untrimmed;
  untrimmed.trimming_rounds = 0;
  const OdometryResult raw = calibrateOdometry(samples, untrimmed);
  const OdometryResult trimmed = calibrateOdometry(samples);
  ASSERT_TRUE(raw.ok() && trimmed.ok());
  const double raw_error = (raw.estimate.toVector() - settings.truth.toVector())
                               .cwiseQuotient(trimmed.standardErrors())
                               .cwiseAbs()
                               .maxCoeff();
  const double trimmed_error = (trimmed.estimate.toVector() - settings.truth.toVector())
                                   .cwiseQuotient(trimmed.standardErrors())
                                   .cwiseAbs()
                                   .maxCoeff();
  EXPECT_GT(raw_error, 2.0 * trimmed_error);
}

TEST(Calibrate, CountsItsSamplesAndFits) {
  SimulationSettings settings;
  settings.samples = 1000;
  const OdometryResult r = calibrateOdometry(simulateSamples(settings));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.samples_total, 1000u);
  EXPECT_EQ(r.samples_used + r.samples_trimmed, 1000u);
  EXPECT_EQ(r.fits, 5);
  // Four rounds of at most 1 % per criterion: at most 2 % a round.
  EXPECT_GE(r.samples_used, 1000u * 92 / 100);
  EXPECT_LT(r.samples_in_covariance, r.samples_used);
  OdometrySettings none;
  none.trimming_rounds = 0;
  const OdometryResult all = calibrateOdometry(simulateSamples(settings), none);
  EXPECT_EQ(all.fits, 1);
  EXPECT_EQ(all.samples_used, 1000u);
}

TEST(Calibrate, DegenerateDrivesGiveAStatusNeverANumber) {
  struct Case {
    MotionMix mix;
    std::size_t samples;
    StatusCode code;
  };
  const Case cases[] = {{{true, false, false, false}, 500, StatusCode::degenerate_motion},
                        {{false, true, false, false}, 500, StatusCode::degenerate_motion},
                        {{}, 5, StatusCode::too_few_samples},
                        {{}, 0, StatusCode::too_few_samples}};
  for (const Case& c : cases) {
    SimulationSettings settings;
    settings.mix = c.mix;
    settings.samples = c.samples;
    const OdometryResult r = calibrateOdometry(simulateSamples(settings));
    EXPECT_EQ(r.status.code, c.code) << r.status.message;
    EXPECT_FALSE(r.status.message.empty());
    EXPECT_TRUE(r.estimate.toVector().allFinite());
    EXPECT_TRUE(r.covariance.allFinite());
  }
}

TEST(Calibrate, RefusesInvalidSettings) {
  OdometrySettings s;
  s.trim_percentile = 40.0;
  EXPECT_THROW(calibrateOdometry({}, s), InputError);
  s = {};
  s.min_samples = 2;
  EXPECT_THROW(calibrateOdometry({}, s), InputError);
  s = {};
  s.trimming_rounds = -1;
  EXPECT_THROW(calibrateOdometry({}, s), InputError);
}

// ---- The published results (Censi et al. 2013, configurations B and C) ----

struct Published {
  Vector6 value;
  Matrix6 covariance;
};

/// X_results.json: diameters (halved here: the covariance is of the radii) and the covariance.
Published readPublished(const std::string& file) {
  std::ifstream in(file);
  const nlohmann::json j = nlohmann::json::parse(in);
  Published p;
  p.value << j["l_diam"].get<double>() / 2.0, j["r_diam"].get<double>() / 2.0,
      j["axle"].get<double>(), j["l_x"].get<double>(), j["l_y"].get<double>(),
      j["l_theta"].get<double>();
  for (int a = 0; a < kParameterCount; ++a)
    for (int b = 0; b < kParameterCount; ++b) p.covariance(a, b) = j["covariance"][a][b];
  return p;
}

class PublishedResult : public ::testing::TestWithParam<const char*> {};

TEST_P(PublishedResult, IsReproducedWithinAFractionOfItsStandardErrors) {
  const auto dir = test::sharedData() / "censi_odometry";
  const std::string name = GetParam();
  if (!std::filesystem::exists(dir / (name + ".tuple"))) GTEST_SKIP() << "no " << dir.string();
  const Published paper = readPublished((dir / (name + "_results.json")).string());
  const OdometryResult r = calibrateOdometry(io::readOdometryTuples(dir / (name + ".tuple")));
  ASSERT_TRUE(r.ok()) << r.status.message;
  const Vector6 paper_error = paper.covariance.diagonal().cwiseSqrt();
  const Vector6 ours = r.estimate.toVector(), our_error = r.standardErrors();
  for (int k = 0; k < kParameterCount; ++k) {
    SCOPED_TRACE(kParameterNames[k]);
    // Measured: within 0.03 of the paper's standard errors (brief: within 1).
    EXPECT_LT(std::abs(ours[k] - paper.value[k]), 0.05 * paper_error[k]);
    // Measured: within 5.5 % (brief: within 20 %).
    EXPECT_NEAR(our_error[k] / paper_error[k], 1.0, 0.06);
  }
}

INSTANTIATE_TEST_SUITE_P(Configurations, PublishedResult, ::testing::Values("l90", "lmov"));

}  // namespace
}  // namespace lidarcal::odometry
