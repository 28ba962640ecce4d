// SPDX-License-Identifier: BSD-3-Clause
// Continuous motion: a robot driving a loop among thin poles, every scan its
// own pose from drifting odometry (data/scenes/driving_small_poles.json, landmark level: no
// detector). The joint refinement with the odometry as a motion prior between consecutive
// poses must bring the poses closer to the truth than the odometry, and closer than tying every
// pose to its own odometry pose (stop and go's prior), which pulls the drifted path back.

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calibration/calibrate.hpp"
#include "calibration/joint_refinement.hpp"
#include "common/pose2.hpp"
#include "common/rng.hpp"
#include "common/stats_util.hpp"
#include "io/scene_io.hpp"
#include "simulation/landmark_level.hpp"
#include "test_util.hpp"

namespace lidarcal::calibration {
namespace {

simulation::LandmarkLevelConfig driving() {
  const Scene scene = io::readScene(test::sourceDir() / "data/scenes/driving_small_poles.json");
  simulation::LandmarkLevelConfig c;
  c.landmarks = scene.landmarks;
  c.path = scene.path;
  c.model = scene.sensor.range;
  c.sigma_theta_rad = deg2rad(0.2);
  c.beams = true;
  c.angle_increment_rad = scene.sensor.angle_increment_rad;
  return c;
}

double positionRms(const std::vector<Pose2>& poses, const std::vector<TruthStop>& truth) {
  double s = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k)
    s += std::pow(poses[k].x_m - truth[k].actual.x_m, 2) +
         std::pow(poses[k].y_m - truth[k].actual.y_m, 2);
  return std::sqrt(s / static_cast<double>(poses.size()));
}

/// A refinement's start: the commanded poses, the true landmarks and range model.
JointInit startAtTheTruth(const simulation::LandmarkLevelConfig& cfg,
                          const LandmarkObservations& obs) {
  JointInit init;
  init.poses = obs.commanded;
  for (std::size_t l = 0; l < cfg.landmarks.size(); ++l)
    init.centres[static_cast<int>(l) + 1] =
        Eigen::Vector2d(cfg.landmarks[l].x_m, cfg.landmarks[l].y_m);
  init.radius_m = cfg.landmarks.front().radius_m;
  init.model = cfg.model;
  return init;
}

TEST(MotionPrior, AutomaticOnlyForContinuousSequences) {
  const auto sample = simulation::simulateLandmarkLevel(driving(), 1);
  EXPECT_TRUE(continuousMotion(sample.obs, JointConfig{}));
  // The same sightings spread over two scans per stop (stop and go): not continuous.
  LandmarkObservations stop_and_go = sample.obs;
  for (std::size_t i = 0; i < stop_and_go.sightings.size(); ++i)
    stop_and_go.sightings[i].scan = 10 * stop_and_go.sightings[i].stop + i % 2;
  EXPECT_FALSE(continuousMotion(stop_and_go, JointConfig{}));
  // Too few poses to call it a drive.
  LandmarkObservations short_run = sample.obs;
  short_run.commanded.resize(10);
  short_run.sightings.erase(std::remove_if(short_run.sightings.begin(), short_run.sightings.end(),
                                           [](const Sighting& s) { return s.stop >= 10; }),
                            short_run.sightings.end());
  EXPECT_FALSE(continuousMotion(short_run, JointConfig{}));
}

TEST(MotionPrior, RefinedPosesBeatTheOdometryAndThePerPosePrior) {
  const auto cfg = driving();
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(seed);
    const auto sample = simulation::simulateLandmarkLevel(cfg, seed);
    ASSERT_GE(sample.obs.commanded.size(), 100u);
    CalibrationConfig cc;
    cc.max_order = 2;
    cc.joint.covariance = false;
    cc.joint.motion = MotionPrior::on;
    const auto with = calibrate(sample.obs, cc);
    ASSERT_STREQ(with.status.name(), "ok") << with.status.message;
    EXPECT_TRUE(with.motion_prior);
    cc.joint.motion = MotionPrior::off;
    const auto without = calibrate(sample.obs, cc);
    ASSERT_STREQ(without.status.name(), "ok") << without.status.message;
    EXPECT_FALSE(without.motion_prior);
    const double odometry = positionRms(sample.obs.commanded, sample.stops);
    const double prior = positionRms(with.stop_poses, sample.stops);
    const double per_pose = positionRms(without.stop_poses, sample.stops);
    // The odometry drifts by several centimetres over the loop (translation 10 %, heading
    // 5 deg/m); the landmarks seen from every pose pin each pose down to about a centimetre.
    EXPECT_GT(odometry, 0.02);
    EXPECT_LT(prior, 0.5 * odometry) << "odometry " << odometry << " per-pose prior " << per_pose;
    EXPECT_LT(prior, per_pose);
    // The range model: within 5 mm of the truth over the fitted distances.
    for (double d = 0.6; d <= 1.4; d += 0.2)
      EXPECT_NEAR(with.model.bias(d), cfg.model.bias(d), 0.005) << "d " << d;
  }
}

// The prior's reported negative log-likelihood is the odometry's Gaussian density at the
// refined poses, translation and heading of every step (and the first pose's tie to its
// commanded pose), each step's deviations at its neighbours' length: a likelihood ratio of two fits
// compares what the refinement minimised. Leaving the heading changes out would miss hundreds
// of nats on this drive.
TEST(MotionPrior, ReportedPriorLikelihoodIsTheOdometrysDensityAtThePoses) {
  const auto cfg = driving();
  const auto sample = simulation::simulateLandmarkLevel(cfg, 4);
  JointConfig jc;
  jc.covariance = false;
  jc.motion = MotionPrior::on;
  const JointResult f = refineJoint(sample.obs, startAtTheTruth(cfg, sample.obs), jc);
  ASSERT_TRUE(f.ok()) << f.status.message;
  ASSERT_TRUE(f.motion_prior);
  ASSERT_EQ(f.poses.size(), sample.obs.commanded.size());
  auto gauss = [](double e, double sd) {
    return 0.5 * e * e / (sd * sd) + 0.5 * kLog2Pi + std::log(sd);
  };
  const auto& c = sample.obs.commanded;
  double expected = gauss(f.poses[0].x_m - c[0].x_m, jc.sigma_s_m) +
                    gauss(f.poses[0].y_m - c[0].y_m, jc.sigma_s_m) +
                    gauss(wrapAngle(f.poses[0].yaw_rad - c[0].yaw_rad), jc.sigma_psi_rad);
  double heading = 0.0;
  for (std::size_t k = 1; k < f.poses.size(); ++k) {
    // Each step seen from the pose before it, commanded and refined.
    const Pose2 want = stepBetween(c[k - 1], c[k]), got = stepBetween(f.poses[k - 1], f.poses[k]);
    const double len = motionStepLength(c, k);
    expected += gauss(got.x_m - want.x_m, jc.motionStepSigma(len)) +
                gauss(got.y_m - want.y_m, jc.motionStepSigma(len));
    const double h = gauss(wrapAngle(got.yaw_rad - want.yaw_rad), jc.motionHeadingSigma(len));
    expected += h;
    heading += h;
  }
  EXPECT_LT(heading, -100.0);  // the heading terms matter: ln sd is about -5 per step
  EXPECT_NEAR(f.prior_neg_log_likelihood, expected, 1e-6 * std::abs(expected));
}

// A step's deviations are taken at the length its neighbours report, not its own: one step
// reported 40 % long among 3 cm steps keeps 3 cm (the odometry's noise), one ten times as long
// keeps its own (the robot sped up, or a pose is missing), and where the speed changes the
// length follows it within the window (ten steps either side).
TEST(MotionPrior, AStepIsWeighedAtTheLengthItsNeighboursReport) {
  std::vector<Pose2> c{Pose2{0.0, 0.0, 0.0}};
  for (int k = 1; k <= 60; ++k) {
    const double step = k == 20 ? 0.042 : k == 10 ? 0.3 : k <= 40 ? 0.03 : 0.06;
    c.push_back(Pose2{c.back().x_m + step, 0.0, 0.0});
  }
  EXPECT_NEAR(motionStepLength(c, 20), 0.03, 1e-12);
  EXPECT_NEAR(motionStepLength(c, 10), 0.3, 1e-12);
  EXPECT_NEAR(motionStepLength(c, 1), 0.03, 1e-12);   // the window clipped at the start
  EXPECT_NEAR(motionStepLength(c, 60), 0.06, 1e-12);  // and at the end
  EXPECT_NEAR(motionStepLength(c, 25), 0.03, 1e-12);  // 20 neighbours, 19 of 3 cm
  EXPECT_NEAR(motionStepLength(c, 55), 0.06, 1e-12);
  // Across the change, the majority of the window (its own within half of that).
  EXPECT_NEAR(motionStepLength(c, 36), 0.03, 1e-12);  // steps 26-46 but 36: 14 of 3 cm, 6 of 6 cm
  EXPECT_NEAR(motionStepLength(c, 46), 0.06, 1e-12);  // steps 36-56 but 46: 5 of 3 cm, 15 of 6 cm
  // steps 30-50 but 40: 10 of 3 cm, 10 of 6 cm; its own 3 cm within half of 4.5
  EXPECT_NEAR(motionStepLength(c, 40), 0.045, 1e-12);
}

// The step scale of a drive is unbiased: odometry that reports every step 1 / (1 + s) times its
// true length, with noise of 10 % of the step (3 cm per scan), gives back s on average. The
// odometry errs in proportion to the step it measures; weighed at the length it reports, a step
// reported short weighed more than one reported long and s came out 1.2 % long on average (one
// drive's standard error is about 0.6 %). Twelve drives whose seeds and scales come from a seed
// the test does not read; the mean error must be within 3 standard errors of the mean of zero.
TEST(MotionPrior, TheStepScaleOfADriveIsUnbiased) {
  auto cfg = driving();
  auto rng = makeRng(20261128, 24);
  std::uniform_int_distribution<std::uint64_t> seed_of(1000, 1000000);
  std::uniform_real_distribution<double> scale_of(-0.03, 0.03);
  std::vector<double> err;
  for (int i = 0; i < 12; ++i) {
    const std::uint64_t seed = seed_of(rng);
    const double truth = scale_of(rng);
    SCOPED_TRACE(seed);
    cfg.path.step_error_fraction = truth;
    const auto sample = simulation::simulateLandmarkLevel(cfg, seed);
    JointConfig jc;
    jc.covariance = false;
    jc.motion = MotionPrior::on;
    jc.effects.odometry_scale = true;
    const JointResult f = refineJoint(sample.obs, startAtTheTruth(cfg, sample.obs), jc);
    ASSERT_TRUE(f.ok()) << f.status.message;
    err.push_back(f.effects.odometry_scale - truth);
  }
  double mean = 0.0, var = 0.0;
  for (double e : err) mean += e / static_cast<double>(err.size());
  for (double e : err) var += (e - mean) * (e - mean) / static_cast<double>(err.size() - 1);
  const double se = std::sqrt(var / static_cast<double>(err.size()));
  // --gtest_output=xml shows them
  ::testing::Test::RecordProperty("mean_error", std::to_string(mean));
  ::testing::Test::RecordProperty("standard_error", std::to_string(se));
  EXPECT_GT(se, 0.0005);  // the drives differ: a spread of about half a percent each
  EXPECT_LT(std::abs(mean), 3.0 * se) << "mean error " << mean << " standard error " << se;
}

}  // namespace
}  // namespace lidarcal::calibration
