// SPDX-License-Identifier: BSD-3-Clause
// The closed form: noise-free samples give the truth back exactly; motions that leave a
// parameter undetermined, too few samples and swapped wheels give a status, never a NaN.

#include <cmath>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>

#include "odometry/closed_form.hpp"
#include "odometry/motion_model.hpp"
#include "odometry/simulated_samples.hpp"

namespace lidarcal::odometry {
namespace {

std::vector<std::size_t> all(const std::vector<OdometrySample>& samples) {
  std::vector<std::size_t> i(samples.size());
  std::iota(i.begin(), i.end(), std::size_t{0});
  return i;
}

SimulationSettings noiseFree(const OdometryParameters& truth, std::uint64_t seed) {
  SimulationSettings s;
  s.truth = truth;
  s.samples = 300;
  s.sigma_x_m = s.sigma_y_m = s.sigma_theta_rad = 0.0;
  s.seed = seed;
  return s;
}

class NoiseFree : public ::testing::TestWithParam<OdometryParameters> {};

TEST_P(NoiseFree, RecoversTheTruthExactly) {
  const OdometryParameters truth = GetParam();
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    const std::vector<OdometrySample> samples = simulateSamples(noiseFree(truth, seed));
    const ClosedFormFit fit = fitClosedForm(samples, all(samples), OdometrySettings{});
    ASSERT_TRUE(fit.ok()) << fit.status.message;
    const Vector6 got = fit.params.toVector(), want = truth.toVector();
    for (int k = 0; k < kParameterCount; ++k)
      EXPECT_NEAR(got[k], want[k], 1e-10 * std::max(1.0, std::abs(want[k]))) << k;
    EXPECT_LT(fit.lambda_m2, 1e-14);  // rounding: the normal matrix's entries are ~1-10
    EXPECT_NEAR(fit.j21, -truth.left_radius_m / truth.axle_m, 1e-12);
    EXPECT_NEAR(fit.j22, truth.right_radius_m / truth.axle_m, 1e-12);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Robots, NoiseFree,
    ::testing::Values(OdometryParameters{0.0206, 0.0207, 0.088, -0.0026, 0.0058, -1.558},
                      OdometryParameters{0.0207, 0.0208, 0.0884, -0.0059, -0.0387, -1.860},
                      OdometryParameters{0.1, 0.098, 0.5, 0.3, -0.05, 3.1},
                      OdometryParameters{0.05, 0.05, 0.3, 0.0, 0.0, 0.0}));

TEST(ClosedForm, TheMultiplierIsTheSumOfSquaredLoopResiduals) {
  // At the solution each sample's loop residual L m is R(l_theta) times its translation
  // residual, so lambda equals the sum of the squared translation residuals.
  SimulationSettings settings;
  settings.samples = 200;
  const std::vector<OdometrySample> samples = simulateSamples(settings);
  const ClosedFormFit fit = fitClosedForm(samples, all(samples), OdometrySettings{});
  ASSERT_TRUE(fit.ok());
  double sum = 0.0;
  for (const OdometrySample& s : samples)
    sum += scanMatchResidual(fit.params, s).head<2>().squaredNorm();
  EXPECT_GT(fit.lambda_m2, 0.0);
  EXPECT_NEAR(fit.lambda_m2, sum, 1e-9 * sum);
}

/// Samples of a drive with only the motions enabled in `mix` and some noise.
std::vector<OdometrySample> drive(MotionMix mix, std::size_t n = 300) {
  SimulationSettings s;
  s.mix = mix;
  s.samples = n;
  return simulateSamples(s);
}

void expectRefusal(const ClosedFormFit& fit, StatusCode code) {
  EXPECT_EQ(fit.status.code, code) << fit.status.message;
  EXPECT_FALSE(fit.status.message.empty());
  EXPECT_TRUE(fit.params.toVector().allFinite());
}

TEST(ClosedForm, OnlyStraightDrivingCannotSeparateTheWheels) {
  const auto samples = drive({true, false, false, false});
  expectRefusal(fitClosedForm(samples, all(samples), {}), StatusCode::degenerate_motion);
}

TEST(ClosedForm, OnlyTurningInPlaceCannotSeparateTheWheels) {
  const auto samples = drive({false, true, false, false});
  expectRefusal(fitClosedForm(samples, all(samples), {}), StatusCode::degenerate_motion);
}

TEST(ClosedForm, NoMotionAtAllIsDegenerate) {
  std::vector<OdometrySample> still(100);
  for (auto& s : still) s.duration_s = 0.8;
  expectRefusal(fitClosedForm(still, all(still), {}), StatusCode::degenerate_motion);
}

TEST(ClosedForm, StraightDrivingAndTurningInPlaceTogetherSuffice) {
  // Each alone is degenerate; together they determine all six parameters.
  const auto samples = drive({true, true, false, false});
  EXPECT_TRUE(fitClosedForm(samples, all(samples), {}).ok());
}

TEST(ClosedForm, TooFewSamplesIsAStatus) {
  const auto samples = drive(MotionMix{}, 11);
  expectRefusal(fitClosedForm(samples, all(samples), {}), StatusCode::too_few_samples);
  const std::vector<OdometrySample> none;
  expectRefusal(fitClosedForm(none, {}, {}), StatusCode::too_few_samples);
}

TEST(ClosedForm, SwappedWheelsNeedANegativeAxle) {
  // phi_l and phi_r exchanged: the robot seems to turn the wrong way for its wheels.
  std::vector<OdometrySample> samples = drive(MotionMix{});
  for (auto& s : samples) std::swap(s.left_wheel_rad_s, s.right_wheel_rad_s);
  expectRefusal(fitClosedForm(samples, all(samples), {}), StatusCode::negative_axle);
}

TEST(ClosedForm, OneWheelWithItsSignFlippedIsRefused) {
  std::vector<OdometrySample> samples = drive(MotionMix{});
  for (auto& s : samples) s.left_wheel_rad_s = -s.left_wheel_rad_s;
  expectRefusal(fitClosedForm(samples, all(samples), {}), StatusCode::negative_axle);
}

}  // namespace
}  // namespace lidarcal::odometry
