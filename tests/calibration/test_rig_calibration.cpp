// SPDX-License-Identifier: BSD-3-Clause
// Joint calibration of several lidars on one vehicle (calibration/rig_calibrate.hpp) against
// simulated rigs whose truth the test sets: mountings, range models, vehicle poses. The coverage
// of the standard errors over many seeds is bench/rig_coverage.cpp's job; here a few seeds each.

#include <cmath>

#include <gtest/gtest.h>

#include "calibration/rig_calibrate.hpp"
#include "calibration/rig_scenes.hpp"

namespace lidarcal::test {
namespace {

using calibration::RigConfig;
using calibration::RigFrame;
using calibration::RigResult;

RigConfig configFor(const simulation::RigSimConfig& sim) {
  RigConfig c;
  c.orders.assign(sim.sensors.size(), 1);
  if (sim.use_driving) {
    c.sigma_vehicle_m = 0.002;
    c.sigma_vehicle_rad = 0.001;
    c.motion_sigma_fraction = sim.driving.driving.odometry.translation_fraction;
    c.motion_sigma_floor_m = 1e-4;
    c.motion_heading_sigma_rad_per_m = sim.driving.driving.odometry.heading_rad_per_m;
    c.motion_heading_floor_rad = 1e-4;
  } else if (sim.sigma_s_m > 0.0) {
    c.sigma_vehicle_m = sim.sigma_s_m;
    c.sigma_vehicle_rad = sim.sigma_psi_rad;
  }
  return c;
}

/// Each mounting (vehicle frame) within k standard errors of the truth.
void expectMountingsWithin(const RigResult& r, const simulation::RigSimConfig& sim, double k) {
  ASSERT_TRUE(r.ok()) << r.status.message;
  for (std::size_t s = 0; s < sim.sensors.size(); ++s) {
    SCOPED_TRACE(sim.sensors[s].name);
    const auto& e = r.sensors[s];
    const Mounting& t = sim.sensors[s].mounting;
    EXPECT_LE(std::abs(e.mounting.x_m - t.x_m), k * std::sqrt(e.mounting_covariance(0, 0)));
    EXPECT_LE(std::abs(e.mounting.y_m - t.y_m), k * std::sqrt(e.mounting_covariance(1, 1)));
    EXPECT_LE(std::abs(wrapAngle(e.mounting.yaw_rad - t.yaw_rad)),
              k * std::sqrt(e.mounting_covariance(2, 2)));
    EXPECT_EQ(e.mounting.upside_down, t.upside_down);
  }
}

TEST(RigCalibration, NoiseFreeReadingsGiveTheExactMountingsAndModels) {
  simulation::RigSimConfig sim = stopAndGo(false);
  for (auto& s : sim.sensors) s.model.noise.sigma_e = 1e-6;
  sim.sigma_s_m = 0.0;
  sim.sigma_psi_rad = 0.0;
  RigConfig c = configFor(sim);
  const RigResult r = calibration::calibrateRig(simulation::simulateRig(sim, 3).obs, c);
  ASSERT_TRUE(r.ok()) << r.status.message;
  EXPECT_EQ(r.frame, RigFrame::vehicle);
  for (std::size_t s = 0; s < sim.sensors.size(); ++s) {
    SCOPED_TRACE(sim.sensors[s].name);
    const auto& e = r.sensors[s];
    EXPECT_NEAR(e.mounting.x_m, sim.sensors[s].mounting.x_m, 1e-4);
    EXPECT_NEAR(e.mounting.y_m, sim.sensors[s].mounting.y_m, 1e-4);
    EXPECT_NEAR(e.mounting.yaw_rad, sim.sensors[s].mounting.yaw_rad, 1e-5);
    EXPECT_NEAR(e.model.bias.alpha[0], sim.sensors[s].model.bias.alpha[0], 1e-4);
    EXPECT_NEAR(e.model.bias.alpha[1], sim.sensors[s].model.bias.alpha[1], 1e-4);
  }
}

TEST(RigCalibration, StopAndGoRecoversTwoAndThreeMountingsInTheVehicleFrame) {
  for (const bool three : {false, true})
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      SCOPED_TRACE(seed);
      const simulation::RigSimConfig sim = stopAndGo(three);
      const RigResult r =
          calibration::calibrateRig(simulation::simulateRig(sim, seed).obs, configFor(sim));
      EXPECT_EQ(r.frame, RigFrame::vehicle);
      EXPECT_FALSE(r.scale_free);
      expectMountingsWithin(r, sim, 4.0);
    }
}

TEST(RigCalibration, ADrivingVehicleRecoversItsMountingsWithTheOdometryAsMotionPrior) {
  const simulation::RigSimConfig sim = driving(false);
  const RigResult r =
      calibration::calibrateRig(simulation::simulateRig(sim, 2).obs, configFor(sim));
  EXPECT_TRUE(r.motion_prior);
  expectMountingsWithin(r, sim, 4.0);
}

/// An estimate fitted over [lo, hi] metres with bias coefficients `alpha` known to 1 mm and 1e-4.
calibration::RigSensorEstimate fittedOver(std::vector<double> alpha, double lo, double hi) {
  calibration::RigSensorEstimate e;
  e.model.bias.alpha = std::move(alpha);
  e.alpha_covariance = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(e.model.bias.alpha.size()),
                                             static_cast<Eigen::Index>(e.model.bias.alpha.size()));
  e.alpha_covariance(0, 0) = 1e-6;
  e.alpha_covariance(1, 1) = 1e-8;
  e.d_min_m = lo;
  e.d_max_m = hi;
  return e;
}

TEST(RigCalibration, ARangeModelBeyondWhatLidarsAreBuiltToIsNotDeterminedHoweverSmallItsErrors) {
  const RigConfig c;
  // A 4 % scale error and a 12 mm offset over 1-8 m: a range error, kept.
  calibration::RigSensorEstimate plain = fittedOver({0.012, 1.04}, 1.0, 8.0);
  calibration::checkRangeModel(plain, "front", c);
  EXPECT_TRUE(plain.model_status.ok()) << plain.model_status.message;
  // A quadratic that moves readings by 180 mm at 0.55 m over 0.55-1.01 m (a short span where
  // the polynomial trades off against the mounting): refused, naming the span.
  calibration::RigSensorEstimate bent = fittedOver({1.14, -1.77, 1.85}, 0.55, 1.01);
  calibration::checkRangeModel(bent, "back", c);
  EXPECT_EQ(bent.model_status.code, StatusCode::not_identifiable);
  EXPECT_NE(bent.model_status.message.find("0.55-1.01 m"), std::string::npos)
      << bent.model_status.message;
  // The same polynomial's standard error alone would pass it.
  EXPECT_LT(bent.model_se_m, c.max_model_se_m);
  // Just inside and just outside the bound (25 % of the distance at 2 m: 500 mm).
  calibration::RigSensorEstimate inside = fittedOver({0.49, 1.0}, 2.0, 4.0),
                                 outside = fittedOver({0.51, 1.0}, 2.0, 4.0);
  calibration::checkRangeModel(inside, "a", c);
  calibration::checkRangeModel(outside, "b", c);
  EXPECT_TRUE(inside.model_status.ok());
  EXPECT_FALSE(outside.model_status.ok());
}

TEST(RigCalibration, EachSensorGetsItsOwnNoiseLaw) {
  const simulation::RigSimConfig sim = stopAndGo(true);  // the side lidar's noise grows with f(d)^2
  const RigResult r =
      calibration::calibrateRig(simulation::simulateRig(sim, 1).obs, configFor(sim));
  ASSERT_TRUE(r.ok()) << r.status.message;
  EXPECT_EQ(r.sensors[0].model.noise.kind, NoiseKind::constant);
  EXPECT_EQ(r.sensors[2].model.noise.kind, NoiseKind::squared);
  EXPECT_NEAR(r.sensors[0].model.noise.sigma_e, 0.004, 0.0005);
  EXPECT_NEAR(r.sensors[2].model.noise.sigma_e, 0.002, 0.0004);
}

TEST(RigCalibration, AStaticVehicleGivesTheRelativeMountingsOnlyAndSaysWhy) {
  const simulation::RigSimConfig sim = staticVehicle(false);
  const RigResult r =
      calibration::calibrateRig(simulation::simulateRig(sim, 4).obs, configFor(sim));
  ASSERT_TRUE(r.ok()) << r.status.message;
  EXPECT_EQ(r.frame, RigFrame::relative);
  EXPECT_TRUE(r.scale_free);
  EXPECT_TRUE(r.sensors[0].mounting_held);
  EXPECT_TRUE(r.sensors[0].scale_held);
  ASSERT_EQ(r.relative.size(), 1u);
  const auto& rel = r.relative.front();
  const Pose2 truth = relativeMounting(sim.sensors[0].mounting, sim.sensors[1].mounting);
  const double scale = sim.sensors[0].model.bias.alpha[1];  // lengths in the reference's units
  EXPECT_LE(std::abs(rel.pose.x_m - scale * truth.x_m), 4.0 * std::sqrt(rel.covariance(0, 0)));
  EXPECT_LE(std::abs(rel.pose.y_m - scale * truth.y_m), 4.0 * std::sqrt(rel.covariance(1, 1)));
  EXPECT_LE(std::abs(wrapAngle(rel.pose.yaw_rad - truth.yaw_rad)),
            4.0 * std::sqrt(rel.covariance(2, 2)));
  bool scale_note = false, frame_note = false;
  for (const auto& n : r.notes) {
    scale_note = scale_note || n.find("range scale") != std::string::npos;
    frame_note = frame_note || n.find("relative to front") != std::string::npos;
  }
  EXPECT_TRUE(scale_note && frame_note);
}

TEST(RigCalibration, TheVehicleFrameOfAStaticVehicleIsRefusedWithWhatToRecord) {
  const simulation::RigSimConfig sim = staticVehicle(false);
  RigConfig c = configFor(sim);
  c.frame = RigFrame::vehicle;
  const RigResult r = calibration::calibrateRig(simulation::simulateRig(sim, 4).obs, c);
  EXPECT_EQ(r.status.code, StatusCode::not_identifiable);
  EXPECT_NE(r.status.message.find("turns"), std::string::npos) << r.status.message;
}

TEST(RigCalibration, ASensorThatSharesNoPoleIsRefusedOnAStaticVehicle) {
  simulation::RigSimConfig sim = staticVehicle(false);
  // one in each sensor's view only
  sim.poles = {Cylinder{3.0, 1.2, 0.045}, Cylinder{-1.5, -1.6, 0.045}};
  const RigResult r =
      calibration::calibrateRig(simulation::simulateRig(sim, 1).obs, configFor(sim));
  EXPECT_EQ(r.status.code, StatusCode::no_shared_landmark) << r.status.message;
}

TEST(RigCalibration, AnUnknownFlipIsFoundByItsLikelihood) {
  simulation::RigSimConfig sim = stopAndGo(false);
  const simulation::RigSimSample sample = simulation::simulateRig(sim, 5);
  RigObservations obs = sample.obs;
  obs.sensors[1].prior_known = false;
  obs.sensors[1].prior.upside_down = false;  // the truth is upside down
  const RigResult r = calibration::calibrateRig(obs, configFor(sim));
  ASSERT_TRUE(r.ok()) << r.status.message;
  EXPECT_TRUE(r.sensors[1].mounting.upside_down);
  EXPECT_GT(r.sensors[1].flip_log_likelihood_ratio, 10.0);
}

TEST(RigCalibration, MovingTheWholeSceneLeavesTheMountingsWhereTheyAre) {
  const simulation::RigSimConfig sim = stopAndGo(false);
  const simulation::RigSimSample sample = simulation::simulateRig(sim, 6);
  RigObservations moved = sample.obs;
  const Pose2 shift{5.0, -3.0, 0.7};
  for (Pose2& v : moved.vehicle) v = compose(shift, v);
  const RigResult a = calibration::calibrateRig(sample.obs, configFor(sim));
  const RigResult b = calibration::calibrateRig(moved, configFor(sim));
  ASSERT_TRUE(a.ok() && b.ok());
  for (std::size_t s = 0; s < a.sensors.size(); ++s) {
    EXPECT_NEAR(a.sensors[s].mounting.x_m, b.sensors[s].mounting.x_m, 1e-5);
    EXPECT_NEAR(a.sensors[s].mounting.y_m, b.sensors[s].mounting.y_m, 1e-5);
    EXPECT_NEAR(a.sensors[s].mounting.yaw_rad, b.sensors[s].mounting.yaw_rad, 1e-6);
  }
}

TEST(RigCalibration, TheBiasOrderIsChosenPerSensor) {
  simulation::RigSimConfig sim = stopAndGo(false);
  sim.sensors[1].model.bias.alpha = {-0.01, 1.01, -0.004};  // a bend the other lidar does not have
  RigConfig c = configFor(sim);
  c.orders.clear();
  const RigResult r = calibration::calibrateRig(simulation::simulateRig(sim, 2).obs, c);
  ASSERT_TRUE(r.ok()) << r.status.message;
  EXPECT_EQ(r.sensors[0].model.bias.order(), 1);
  EXPECT_EQ(r.sensors[1].model.bias.order(), 2);
}

}  // namespace
}  // namespace lidarcal::test
