// SPDX-License-Identifier: BSD-3-Clause
// The simulator against the model it implements.

#include <cmath>
#include <numeric>

#include <gtest/gtest.h>

#include "simulation/simulator.hpp"

namespace lidarcal::simulation {
namespace {

/// One stop facing a long wall at distance d_m straight ahead; beam 0 hits it head on.
Scene wallScene(double d_m, const NoiseModel& noise, int scans) {
  Scene s;
  s.sensor.beams = 4;
  s.sensor.angle_increment_rad = deg2rad(90.0);
  s.sensor.range.range_min_m = 0.05;
  s.sensor.range.range_max_m = 50.0;
  s.sensor.range.bias.alpha = {0.0525, 0.8838, 0.0584};
  s.sensor.range.noise = noise;
  s.path.stops = 1;
  s.path.scans_per_stop = scans;
  s.walls.push_back(Segment{d_m, -10.0, d_m, 10.0});
  return s;
}

struct NoiseCase {
  const char* name;
  NoiseModel noise;
};

class NoiseStatistics : public ::testing::TestWithParam<NoiseCase> {};

// Mean and variance of the readings at fixed distances match the model within confidence bounds.
TEST_P(NoiseStatistics, MeanAndVarianceMatchTheModelAtFixedDistances) {
  constexpr int kScans = 4000;
  for (double d : {0.5, 1.5, 3.0, 4.5}) {
    SCOPED_TRACE(d);
    const Scene scene = wallScene(d, GetParam().noise, kScans);
    const auto stops = planStops(scene, 11);
    std::vector<double> r;
    for (int i = 0; i < kScans; ++i) {
      const auto sim = simulateScan(scene, stops[0], static_cast<std::size_t>(i), 11);
      const auto& p = (*sim.scan.cloud)[0];
      ASSERT_TRUE(std::isfinite(p.x));
      EXPECT_NEAR(sim.truth[0].range_m, d, 1e-12);
      r.push_back(p.x);  // beam 0 points along x
    }
    const double mean = std::accumulate(r.begin(), r.end(), 0.0) / kScans;
    double var = 0.0;
    for (double v : r) var += (v - mean) * (v - mean);
    var /= (kScans - 1);
    const double f = scene.sensor.range.bias(d);
    const double sigma = scene.sensor.range.noise.stddev(d, scene.sensor.range.bias);
    // 4.5-sigma bounds: mean ~ N(f, sigma^2/n); var/sigma^2 ~ 1 +- sqrt(2/(n-1)).
    EXPECT_NEAR(mean, f, 4.5 * sigma / std::sqrt(kScans) + 1e-6);  // + float rounding of the point
    EXPECT_NEAR(var / (sigma * sigma), 1.0, 4.5 * std::sqrt(2.0 / (kScans - 1)));
  }
}

NoiseModel squaredNoise() {
  NoiseModel n;
  n.kind = NoiseKind::squared;
  n.sigma_e = 0.0019176;  // about 2 cm at 3 m
  return n;
}

NoiseModel polynomialNoise() {
  NoiseModel n;
  n.kind = NoiseKind::polynomial;
  // Alhashimi et al. 2021 section 4.1: beta = 0.05 alpha
  n.beta = {0.05 * 0.0525, 0.05 * 0.8838, 0.05 * 0.0584};
  return n;
}

INSTANTIATE_TEST_SUITE_P(BothForms, NoiseStatistics,
                         ::testing::Values(NoiseCase{"alhashimi2016_squared", squaredNoise()},
                                           NoiseCase{"alhashimi2021_polynomial",
                                                     polynomialNoise()}),
                         [](const auto& p) { return std::string(p.param.name); });

TEST(Simulator, NoiseFreeReadingsAreTheBiasOfTheTrueRange) {
  Scene scene = wallScene(2.0, NoiseModel{NoiseKind::none, {}, 0.0, 2.0}, 1);
  scene.sensor.beams = 360;
  scene.sensor.angle_increment_rad = deg2rad(1.0);
  scene.landmarks.push_back(Cylinder{1.0, 1.0, 0.2});
  const auto stops = planStops(scene, 3);
  const auto sim = simulateScan(scene, stops[0], 0, 3);
  int landmark_beams = 0;
  for (std::size_t b = 0; b < sim.truth.size(); ++b) {
    const auto& p = (*sim.scan.cloud)[b];
    const auto& t = sim.truth[b];
    if (t.target == io::TargetKind::none) {
      EXPECT_TRUE(std::isnan(p.x));
      continue;
    }
    ASSERT_TRUE(std::isfinite(p.x)) << b;
    EXPECT_NEAR(std::hypot(p.x, p.y), scene.sensor.range.bias(t.range_m), 2e-6);
    EXPECT_NEAR(std::atan2(p.y, p.x), wrapAngle(deg2rad(static_cast<double>(b))), 1e-6);
    landmark_beams += t.target == io::TargetKind::landmark;
  }
  // The pole of radius 0.2 at distance sqrt(2) spans 2 asin(0.2 / sqrt 2) = 16.3 degrees.
  EXPECT_GE(landmark_beams, 15);
  EXPECT_LE(landmark_beams, 17);
}

TEST(Simulator, StopsFollowTheCommandedLineAndScatterByTheirSigma) {
  Scene scene;
  scene.path.start = Pose2{1.0, 2.0, deg2rad(30.0)};
  scene.path.stops = 2000;
  scene.path.step_m = 0.3;
  scene.path.sigma_s_m = 0.02;
  scene.path.sigma_psi_rad = deg2rad(0.5);
  const auto stops = planStops(scene, 5);
  ASSERT_EQ(stops.size(), 2000u);
  double sx = 0, sy = 0, syaw = 0;
  for (std::size_t k = 0; k < stops.size(); ++k) {
    const auto& s = stops[k];
    EXPECT_NEAR(s.commanded.x_m, 1.0 + 0.3 * k * std::cos(deg2rad(30.0)), 1e-9);
    EXPECT_NEAR(s.commanded.y_m, 2.0 + 0.3 * k * std::sin(deg2rad(30.0)), 1e-9);
    sx += std::pow(s.actual.x_m - s.commanded.x_m, 2);
    sy += std::pow(s.actual.y_m - s.commanded.y_m, 2);
    syaw += std::pow(wrapAngle(s.actual.yaw_rad - s.commanded.yaw_rad), 2);
  }
  const double n = static_cast<double>(stops.size());
  const double tol = 4.5 * std::sqrt(2.0 / n);
  EXPECT_NEAR(sx / n / (0.02 * 0.02), 1.0, tol);
  EXPECT_NEAR(sy / n / (0.02 * 0.02), 1.0, tol);
  EXPECT_NEAR(syaw / n / std::pow(deg2rad(0.5), 2), 1.0, tol);
}

TEST(Simulator, AScanDoesNotDependOnWhichScansWereSimulatedBefore) {
  Scene scene = wallScene(3.0, squaredNoise(), 5);
  const auto stops = planStops(scene, 9);
  const auto alone = simulateScan(scene, stops[0], 3, 9);
  for (std::size_t i = 0; i < 3; ++i) simulateScan(scene, stops[0], i, 9);
  const auto after = simulateScan(scene, stops[0], 3, 9);
  for (std::size_t b = 0; b < alone.scan.cloud->size(); ++b) {
    const auto& p = (*alone.scan.cloud)[b];
    const auto& q = (*after.scan.cloud)[b];
    if (std::isnan(p.x))
      EXPECT_TRUE(std::isnan(q.x));
    else
      EXPECT_EQ(p.x, q.x);
  }
  EXPECT_NE((*alone.scan.cloud)[0].x, (*simulateScan(scene, stops[0], 4, 9).scan.cloud)[0].x);
}

TEST(Simulator, ReadingsOutsideTheSensorWindowAreBeamsWithoutReturn) {
  Scene scene = wallScene(5.5, NoiseModel{NoiseKind::none, {}, 0.0, 2.0}, 1);
  scene.sensor.range.range_max_m = 6.0;  // f(5.5) = 6.68 > 6: no return although the wall is there
  const auto stops = planStops(scene, 1);
  const auto sim = simulateScan(scene, stops[0], 0, 1);
  EXPECT_TRUE(std::isnan((*sim.scan.cloud)[0].x));
  EXPECT_NEAR(sim.truth[0].range_m, 5.5, 1e-12);
}

}  // namespace
}  // namespace lidarcal::simulation
