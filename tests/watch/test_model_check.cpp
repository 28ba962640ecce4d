// SPDX-License-Identifier: BSD-3-Clause
// The check's replicas (model_check.hpp): readings drawn from a fit whose poses, poles, curve and
// noise the test sets, against distances the test computes from the geometry itself.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "watch/model_check.hpp"

namespace lidarcal::watch {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// A fit of one pole at (3, 4), radius 0.05, seen from one pose per scan.
CalibrationModel poleFit(NoiseKind noise, double sigma_m) {
  CalibrationModel fit;
  fit.model.bias.alpha = {0.012, 1.004};
  fit.model.noise.kind = noise;
  fit.model.noise.sigma_e = sigma_m;
  fit.stop_poses = {Pose2{1.0, 2.0, 0.3}, Pose2{1.5, 1.8, 0.5}};
  CalibratedLandmark pole;
  pole.id = 7;
  pole.x_m = 3.0;
  pole.y_m = 4.0;
  pole.radius_m = 0.05;
  fit.landmarks = {pole};
  return fit;
}

/// Sightings of the pole from both poses, beams a quarter of a degree apart across it, each
/// recorded `repeats` times; the readings are placeholders the replica replaces.
LandmarkObservations sightings(const CalibrationModel& fit, int repeats) {
  LandmarkObservations obs;
  obs.commanded = fit.stop_poses;
  obs.landmark_radius_m = 0.05;
  const auto& pole = fit.landmarks.front();
  for (int k = 0; k < repeats; ++k)
    for (std::size_t stop = 0; stop < fit.stop_poses.size(); ++stop) {
      const Pose2& p = fit.stop_poses[stop];
      Sighting s;
      s.stop = s.scan = stop;
      s.landmark = pole.id;
      const double centre = std::atan2(pole.y_m - p.y_m, pole.x_m - p.x_m) - p.yaw_rad;
      for (int b = -2; b <= 2; ++b) s.beams.push_back({centre + b * 0.25 * kPi / 180.0, -1.0});
      obs.sightings.push_back(s);
    }
  return obs;
}

/// Distance from (px, py) along `angle` to the circle (cx, cy, r), by the quadratic in t.
double entry(double px, double py, double angle, double cx, double cy, double r) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  const double ox = px - cx, oy = py - cy;
  const double b = ox * dx + oy * dy, c = ox * ox + oy * oy - r * r;
  return -b - std::sqrt(b * b - c);
}

TEST(CheckReplica, WithoutNoiseReadsTheFittedCurveAtTheFittedCircle) {
  const CalibrationModel fit = poleFit(NoiseKind::none, 0.0);
  const LandmarkObservations obs = sightings(fit, 1);
  const LandmarkObservations rep = replicaObservations(obs, fit, 5);
  ASSERT_EQ(rep.sightings.size(), obs.sightings.size());
  for (const Sighting& s : rep.sightings) {
    const Pose2& p = fit.stop_poses[s.stop];
    EXPECT_NEAR(s.centre_range_m, std::hypot(3.0 - p.x_m, 4.0 - p.y_m), 1e-12);
    EXPECT_NEAR(s.bearing_rad, std::atan2(4.0 - p.y_m, 3.0 - p.x_m) - p.yaw_rad, 1e-12);
    for (const BeamReading& b : s.beams) {
      const double d = entry(p.x_m, p.y_m, p.yaw_rad + b.angle_rad, 3.0, 4.0, 0.05);
      EXPECT_NEAR(b.range_m, 0.012 + 1.004 * d, 1e-9);
    }
  }
}

TEST(CheckReplica, DrawsTheFittedNoiseAndRepeatsWithItsSeed) {
  const CalibrationModel fit = poleFit(NoiseKind::constant, 0.01);
  const CalibrationModel exact = poleFit(NoiseKind::none, 0.0);
  const LandmarkObservations obs = sightings(fit, 2000);
  const LandmarkObservations rep = replicaObservations(obs, fit, 11);
  const LandmarkObservations mean = replicaObservations(obs, exact, 11);
  double sum = 0.0, sum2 = 0.0, n = 0.0;
  for (std::size_t i = 0; i < rep.sightings.size(); ++i)
    for (std::size_t j = 0; j < rep.sightings[i].beams.size(); ++j) {
      const double e = rep.sightings[i].beams[j].range_m - mean.sightings[i].beams[j].range_m;
      sum += e, sum2 += e * e, n += 1.0;
    }
  // 20,000 draws: the mean within 5 standard errors of 0, the deviation within 3 % of 10 mm.
  EXPECT_NEAR(sum / n, 0.0, 5.0 * 0.01 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sum2 / n - (sum / n) * (sum / n)), 0.01, 3e-4);
  const LandmarkObservations again = replicaObservations(obs, fit, 11);
  const LandmarkObservations other = replicaObservations(obs, fit, 12);
  EXPECT_EQ(again.sightings[3].beams[2].range_m, rep.sightings[3].beams[2].range_m);
  EXPECT_NE(other.sightings[3].beams[2].range_m, rep.sightings[3].beams[2].range_m);
}

TEST(CheckReplica, LeavesOutPolesTheFitDidNotLocate) {
  const CalibrationModel fit = poleFit(NoiseKind::none, 0.0);
  LandmarkObservations obs = sightings(fit, 1);
  obs.sightings.front().landmark = 8;
  const LandmarkObservations rep = replicaObservations(obs, fit, 1);
  ASSERT_EQ(rep.sightings.size(), obs.sightings.size() - 1);
  for (const Sighting& s : rep.sightings) EXPECT_EQ(s.landmark, 7);
}

TEST(CheckReplica, LeavesOutPolesTheFitListsButSetAside) {
  // A second pole the fit listed but did not use, with a circle that encloses the poses: beams
  // drawn from it would read below zero.
  CalibrationModel fit = poleFit(NoiseKind::none, 0.0);
  CalibratedLandmark aside = fit.landmarks.front();
  aside.id = 8;
  aside.x_m = 1.2;
  aside.y_m = 1.9;
  aside.radius_m = 1.0;
  aside.status = "degenerate_geometry";
  fit.landmarks.push_back(aside);
  LandmarkObservations obs = sightings(fit, 1);
  obs.sightings.front().landmark = 8;
  const LandmarkObservations rep = replicaObservations(obs, fit, 1);
  ASSERT_EQ(rep.sightings.size(), obs.sightings.size() - 1);
  for (const Sighting& s : rep.sightings) {
    EXPECT_EQ(s.landmark, 7);
    for (const BeamReading& b : s.beams) EXPECT_GT(b.range_m, 0.0);
  }
}

TEST(ModelCheckShift, TheTestedShiftTakesTheFitsOwnBiasOutAndWidensForTheReplicasScatter) {
  ModelCheck c;
  c.shift_m = {0.004, 0.009};
  c.fit_bias_m = {-0.001, -0.002};
  c.covariance << 4e-6, 1e-6, 1e-6, 9e-6;
  const Shift fitted = fittedShift(c);
  EXPECT_EQ(fitted.s, Eigen::Vector2d(0.004, 0.009));
  EXPECT_EQ(fitted.c, c.covariance);
  // Without replicas the bias is unknown and the shift is tested as fitted.
  EXPECT_EQ(unbiasedShift(c).s, fitted.s);
  EXPECT_EQ(unbiasedShift(c).c, fitted.c);
  c.bias_replicas = 4;
  const Shift unbiased = unbiasedShift(c);
  EXPECT_NEAR(unbiased.s(0), 0.005, 1e-15);
  EXPECT_NEAR(unbiased.s(1), 0.011, 1e-15);
  EXPECT_TRUE(unbiased.c.isApprox(1.25 * c.covariance, 1e-15));
}

}  // namespace
}  // namespace lidarcal::watch
