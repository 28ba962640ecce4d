// SPDX-License-Identifier: BSD-3-Clause
// The joint refinement's effect terms (calibration/joint_refinement.hpp), which the sequence
// diagnosis fits its candidates with (diagnosis/sequence/refits.hpp), recover known values.

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
#include "simulation/landmark_level.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

struct Recovery {
  const char* name;
  void (*hide)(simulation::LandmarkLevelConfig&);
  void (*enable)(JointEffects&);
  double (*estimate)(const JointResult&);
  double truth;
  double tolerance;
};

class JointEffectRecovery : public ::testing::TestWithParam<Recovery> {};

TEST_P(JointEffectRecovery, RecoversTheTermFromTheCommandedPoses) {
  const Recovery& r = GetParam();
  auto c = test::paperFieldLandmarkLevel();
  r.hide(c);
  const auto s = simulation::simulateLandmarkLevel(c, 11);
  JointConfig jc;
  jc.keep_all_beams = true;
  jc.reselect = false;
  jc.covariance = false;
  jc.estimate_radius = false;
  jc.effects.estimate_heading = false;
  r.enable(jc.effects);
  JointInit init;
  for (const auto& st : s.stops) init.poses.push_back(st.commanded);
  for (std::size_t l = 0; l < c.landmarks.size(); ++l)
    init.centres[static_cast<int>(l) + 1] = Eigen::Vector2d(c.landmarks[l].x_m, c.landmarks[l].y_m);
  init.radius_m = 0.12;
  init.model = c.model;
  init.model.noise.kind = NoiseKind::squared;
  init.model.noise.sigma_e = 0.0019176;
  const JointResult f = refineJoint(s.obs, init, jc);
  ASSERT_TRUE(f.ok()) << f.status.name() << ": " << f.status.message;
  EXPECT_NEAR(r.estimate(f), r.truth, r.tolerance) << r.name;
  // Signed terms: the fitted sign is the hidden one (the tolerance is below the size, so the
  // check above implies it; stated on its own for the message).
  EXPECT_EQ(std::signbit(r.estimate(f)), std::signbit(r.truth))
      << r.name << ": fitted " << r.estimate(f);
}

INSTANTIATE_TEST_SUITE_P(
    EachTerm, JointEffectRecovery,
    ::testing::Values(
        Recovery{"drift", [](auto& c) { c.effects.range_drift_m_per_scan = 3e-4; },
                 [](auto& e) { e.drift = true; },
                 [](const JointResult& f) { return f.effects.drift_m_per_scan; }, 3e-4, 3e-5},
        Recovery{"angle", [](auto& c) { c.mount_yaw_rad = deg2rad(2.0); },
                 [](auto& e) { e.angle_offset = true; },
                 [](const JointResult& f) { return rad2deg(f.effects.angle_offset_rad); }, 2.0,
                 0.3},
        Recovery{"incidence_bias", [](auto& c) { c.effects.incidence_bias_m = 0.03; },
                 [](auto& e) { e.incidence_bias = true; },
                 [](const JointResult& f) { return f.effects.incidence_bias_m; }, 0.03, 0.005},
        // Every signed term also with the other sign.
        Recovery{"drift_negative", [](auto& c) { c.effects.range_drift_m_per_scan = -3e-4; },
                 [](auto& e) { e.drift = true; },
                 [](const JointResult& f) { return f.effects.drift_m_per_scan; }, -3e-4, 3e-5},
        Recovery{"angle_negative", [](auto& c) { c.mount_yaw_rad = deg2rad(-2.0); },
                 [](auto& e) { e.angle_offset = true; },
                 [](const JointResult& f) { return rad2deg(f.effects.angle_offset_rad); }, -2.0,
                 0.3},
        Recovery{"incidence_bias_negative", [](auto& c) { c.effects.incidence_bias_m = -0.03; },
                 [](auto& e) { e.incidence_bias = true; },
                 [](const JointResult& f) { return f.effects.incidence_bias_m; }, -0.03, 0.005},
        Recovery{"landmark_offset_negative", [](auto& c) { c.landmarks[2].range_offset_m = -0.04; },
                 [](auto& e) { e.landmark_offsets = true; },
                 [](const JointResult& f) {
                   return f.effects.landmark_offset_m.at(3) - f.effects.landmark_offset_m.at(1);
                 },
                 -0.04, 0.005},
        Recovery{"landmark_offset", [](auto& c) { c.landmarks[2].range_offset_m = 0.04; },
                 [](auto& e) { e.landmark_offsets = true; },
                 [](const JointResult& f) {
                   return f.effects.landmark_offset_m.at(3) - f.effects.landmark_offset_m.at(1);
                 },
                 0.04, 0.005},
        // The true steps 4 % longer (shorter) than commanded; the radius is given, so the scale
        // is separable from the bias.
        Recovery{"odometry_scale", [](auto& c) { c.path.step_error_fraction = 0.04; },
                 [](auto& e) { e.odometry_scale = true; },
                 [](const JointResult& f) { return f.effects.odometry_scale; }, 0.04, 0.01},
        Recovery{"odometry_scale_negative", [](auto& c) { c.path.step_error_fraction = -0.04; },
                 [](auto& e) { e.odometry_scale = true; },
                 [](const JointResult& f) { return f.effects.odometry_scale; }, -0.04, 0.01},
        Recovery{"incidence_noise", [](auto& c) { c.effects.incidence_noise_exponent = 1.0; },
                 [](auto& e) { e.incidence_noise = true; },
                 [](const JointResult& f) { return f.effects.incidence_noise_exponent; }, 1.0, 0.2},
        Recovery{"noise_exponent",
                 [](auto& c) {
                   c.model.noise.kind = NoiseKind::power;
                   c.model.noise.exponent = 1.0;
                   c.model.noise.sigma_e = 0.006;
                 },
                 [](auto& e) { e.noise_exponent = true; },
                 [](const JointResult& f) { return f.effects.noise_exponent; }, 1.0, 0.2},
        Recovery{"mixed_pixels", [](auto& c) { c.effects.mixed_pixel_fraction = 0.2; },
                 [](auto& e) { e.mixed_pixels = true; },
                 [](const JointResult& f) { return f.effects.mixed_pixel_fraction; }, 0.2, 0.06},
        // Student-t noise of 4 degrees of freedom (same variance): about 5,000 readings hold nu
        // to a few tenths.
        Recovery{"student_noise", [](auto& c) { c.effects.noise_student_dof = 4.0; },
                 [](auto& e) { e.student_noise = true; },
                 [](const JointResult& f) { return f.effects.student_dof; }, 4.0, 1.2},
        // Readings rounded to 1 cm: the grid is found, and the noise scale fitted on the cells is
        // the unrounded noise's (a Gaussian fit's holds the rounding's q^2 / 12 as well, more than
        // the noise itself near the poles); -1 when the grid is not the hidden one.
        Recovery{"quantised", [](auto& c) { c.effects.range_resolution_m = 0.01; },
                 [](auto& e) { e.quantised = true; },
                 [](const JointResult& f) {
                   return f.effects.range_grid_m == 0.01 ? f.model.noise.sigma_e / 0.0019176 : -1.0;
                 },
                 1.0, 0.1},
        // Poles of intensity 20, 40, 80, 160 and 320, noise growing as (I_ref / I)^0.75: a
        // black pole reads 2.8 times as noisy as a mid-grey one.
        Recovery{"dark",
                 [](auto& c) {
                   for (std::size_t l = 0; l < c.landmarks.size(); ++l)
                     c.landmarks[l].intensity = 20.0 * std::pow(2.0, l);
                   c.effects.dark_noise_exponent = 0.75;
                   c.effects.dark_reference_intensity = 80.0;
                 },
                 [](auto& e) { e.dark_noise = true; },
                 [](const JointResult& f) { return f.effects.dark_noise_exponent; }, 0.75, 0.1}),
    [](const auto& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace lidarcal::diagnosis
