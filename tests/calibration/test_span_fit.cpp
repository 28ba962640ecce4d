// SPDX-License-Identifier: BSD-3-Clause
// Calibration from wall-to-wall spans (calibration/span_walls.hpp, span_fit.hpp,
// span_calibration.hpp) on rooms the simulator ray-casts: the true room gives the spans (the
// laser meter), the sensor's bias is the truth the fit must recover within its standard errors;
// what one pair of walls cannot determine is refused as such; a span whose wall is not there
// names the REF.json field.

#include <cmath>

#include <gtest/gtest.h>

#include "calibration/span_calibration.hpp"
#include "common/pose2.hpp"
#include "detectors/wall_tracks.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::calibration {
namespace {

/// A room 6 m x 4.5 m (x from -2.5 to 3.5, y from -2 to 2.5) with a cabinet 0.4 m deep against
/// the wall x = 3.5 (its front at x = 3.1 for y < 0); the sensor at the origin turned 20 degrees.
/// Spans: 6.0 m between the walls x = -2.5 and x = 3.5, 5.6 m from x = -2.5 to the cabinet,
/// 4.5 m between y = -2 and y = 2.5. Normal directions in the sensor frame: x = 3.5 and the
/// cabinet -20 deg, x = -2.5 160 deg, y = -2 -110 deg, y = 2.5 70 deg.
Scene room(const std::vector<double>& alpha, double sigma_m, int scans) {
  Scene s;
  s.sensor.range.bias.alpha = alpha;
  s.sensor.range.noise.kind = sigma_m > 0.0 ? NoiseKind::constant : NoiseKind::none;
  s.sensor.range.noise.sigma_e = sigma_m;
  s.sensor.range.range_min_m = 0.15;
  s.sensor.range.range_max_m = 8.0;
  s.path.start = Pose2{0.0, 0.0, deg2rad(20.0)};
  s.path.stops = 1;
  s.path.scans_per_stop = scans;
  s.walls = {{-2.5, -2.0, 3.5, -2.0}, {3.5, -2.0, 3.5, 2.5}, {3.5, 2.5, -2.5, 2.5},
             {-2.5, 2.5, -2.5, -2.0}, {3.1, -2.0, 3.1, 0.0}, {3.1, 0.0, 3.5, 0.0}};
  return s;
}

ReferenceSpan span(double bearing_a_deg, double bearing_b_deg, double distance_m) {
  ReferenceSpan r;
  r.bearing_a_rad = deg2rad(bearing_a_deg);
  r.bearing_b_rad = deg2rad(bearing_b_deg);
  r.distance_m = distance_m;
  return r;
}

const ReferenceSpan kWalls = span(-20, 160, 6.0), kCabinet = span(-20, 160, 5.6),
                    kAcross = span(-110, 70, 4.5);

/// The walls of every simulated scan, grouped into surfaces as `calibrate --reference` does.
LandmarkObservations observe(const Scene& scene, std::uint64_t seed) {
  LandmarkObservations obs;
  const auto stops = simulation::planStops(scene, seed);
  obs.commanded = {stops[0].commanded};
  obs.range_min_m = scene.sensor.range.range_min_m;
  obs.range_max_m = scene.sensor.range.range_max_m;
  detectors::WallConfig config;
  config.threshold_per_m2 = 0.005;
  for (int i = 0; i < scene.path.scans_per_stop; ++i) {
    const auto sim = simulation::simulateScan(scene, stops[0], static_cast<std::size_t>(i), seed);
    for (auto& w :
         detectors::wallSightings(*sim.scan.cloud, 0, static_cast<std::size_t>(i), config))
      obs.walls.push_back(w);
  }
  detectors::labelWallSurfaces(obs.walls);
  return obs;
}

struct Fitted {
  CalibrationModel model;
  SpanProblem problem;
};

Fitted calibrate(const LandmarkObservations& obs, const std::vector<ReferenceSpan>& spans) {
  Reference ref;
  ref.spans = spans;
  const SpanReadings found = spanReadings(obs, ref);
  for (const auto& m : found.matches) EXPECT_TRUE(m.ok()) << m.field << ": " << m.status;
  Fitted f;
  f.problem = spanProblem(found, ref, {});
  f.model = calibrateWithSpans(obs, f.problem, {}, CalibrationConfig{});
  return f;
}

/// Standard error of f(d) from the model's covariance.
double biasSe(const CalibrationModel& m, double d) {
  const std::size_t n = m.model.bias.alpha.size();
  double v = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      v += std::pow(d, double(i)) * m.alpha_covariance[i * n + j] * std::pow(d, double(j));
  return std::sqrt(v);
}

// Noise-free readings: the wall's fitted line under the true f is the wall itself.
TEST(SpanFit, WallDistanceUnderTheTrueBiasIsTheTrueDistance) {
  const BiasPolynomial f{{0.02, 1.01, 0.003}};
  SpanWall w;
  w.distance_m = 2.4;  // the raw line: a start, not the answer
  w.normal_rad = deg2rad(31.0);
  for (int j = -40; j <= 25; ++j) {
    const double a = deg2rad(30.0 + j);
    w.beams.push_back(
        {a, f(2.5 / std::cos(a - deg2rad(30.0))), 10, static_cast<std::uint32_t>(j + 40)});
  }
  const WallDistance d = wallDistance(w, f);
  ASSERT_TRUE(d.ok);
  EXPECT_NEAR(d.distance_m, 2.5, 1e-9);
  EXPECT_NEAR(d.normal_rad, deg2rad(30.0), 1e-9);
  EXPECT_LT(d.variance_m2, 1e-20);
}

// Noise-free scans: an offset is recovered exactly, and so is a scale from spans of three lengths.
TEST(SpanFit, NoiseFreeRoomsGiveTheExactBias) {
  for (const std::vector<double>& alpha :
       {std::vector<double>{0.03, 1.0}, std::vector<double>{0.01, 1.02}}) {
    SCOPED_TRACE(alpha[1]);
    const Fitted f = calibrate(observe(room(alpha, 0.0, 2), 1), {kWalls, kCabinet, kAcross});
    ASSERT_TRUE(f.model.status.ok()) << f.model.status.message;
    for (double d : {2.0, 3.0, 4.0})
      EXPECT_NEAR(f.model.model.bias(d), alpha[0] + alpha[1] * d, 2e-4) << d;
  }
}

// A sensor that reads 3 cm long, 5 mm of noise, 10 scans: over 10 rooms the offset at 3 m lies
// within 3 standard errors of the truth, and the raw spans read 2 x 3 cm long.
TEST(SpanFit, AnOffsetIsRecoveredWithinItsStandardError) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE(seed);
    const Fitted f =
        calibrate(observe(room({0.03, 1.0}, 0.005, 10), seed), {kWalls, kCabinet, kAcross});
    ASSERT_TRUE(f.model.status.ok()) << f.model.status.message;
    const double se = biasSe(f.model, 3.0);
    ASSERT_GT(se, 0.0);
    EXPECT_LT(std::abs(f.model.model.bias(3.0) - 3.03), 3.0 * se)
        << "f(3) = " << f.model.model.bias(3.0) << " +- " << se;
    EXPECT_LT(se, 0.005);
    const Eigen::VectorXd raw = entryErrors(f.problem, BiasPolynomial{});
    for (Eigen::Index k = 0; k < raw.size(); ++k) EXPECT_NEAR(raw(k), 0.06, 0.01);
  }
}

// A 2 % scale: spans of three lengths determine it; the offset model alone would leave
// centimetres, so the order chosen is at least 1.
TEST(SpanFit, SpansOfDifferentLengthsRecoverAScale) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    const Fitted f =
        calibrate(observe(room({0.01, 1.02}, 0.005, 10), seed), {kWalls, kCabinet, kAcross});
    ASSERT_TRUE(f.model.status.ok()) << f.model.status.message;
    EXPECT_GE(f.model.order_validation, 1);
    for (double d : {2.5, 3.5}) {
      const double se = biasSe(f.model, d);
      EXPECT_LT(std::abs(f.model.model.bias(d) - (0.01 + 1.02 * d)), 3.0 * se)
          << d << ": +- " << se;
    }
  }
}

// Spans between one pair of walls fix one sum: the offset, never a scale (the order-1 fit is not
// identifiable and the model says so); a second pair of another length makes it identifiable.
TEST(SpanFit, OnePairOfWallsDeterminesAnOffsetOnly) {
  const LandmarkObservations obs = observe(room({0.01, 1.02}, 0.005, 5), 7);
  ReferenceSpan again = kWalls;
  again.distance_m = 6.002;
  const Fitted one = calibrate(obs, {kWalls, again});
  ASSERT_TRUE(one.model.status.ok());
  EXPECT_FALSE(fitSpanModel(one.problem, 1, {true, true}).identifiable);
  EXPECT_TRUE(fitSpanModel(one.problem, 0, {true, true}).identifiable);
  EXPECT_EQ(one.model.order_validation, 0);
  ASSERT_FALSE(one.model.warnings.empty());
  EXPECT_NE(one.model.warnings.front().find("offset only"), std::string::npos)
      << one.model.warnings.front();
  const Fitted two = calibrate(obs, {kWalls, kAcross});
  EXPECT_TRUE(fitSpanModel(two.problem, 1, {true, true}).identifiable);
}

// What a user can get wrong, each named by its field: a bearing where the stop shows no wall, a
// distance no pair of walls there comes near, two bearings whose walls are not parallel.
TEST(SpanWalls, ASpanWithoutItsWallsNamesTheField) {
  const LandmarkObservations obs = observe(room({0.0, 1.0}, 0.005, 3), 2);
  Reference ref;
  ref.spans = {span(-20, 115, 6.0), span(-20, 160, 9.0), span(-20, 70, 4.5)};
  const SpanReadings found = spanReadings(obs, ref);
  ASSERT_EQ(found.matches.size(), 3u);
  EXPECT_EQ(found.matches[0].field, "bearing_b_deg");
  EXPECT_NE(found.matches[0].status.find("no wall within 20 deg of 115 deg"), std::string::npos)
      << found.matches[0].status;
  EXPECT_NE(found.matches[0].status.find("160 deg at 2.50 m"), std::string::npos)
      << "the walls seen are listed: " << found.matches[0].status;
  EXPECT_EQ(found.matches[1].field, "distance_m");
  EXPECT_EQ(found.matches[2].field, "bearing_b_deg");
  EXPECT_NE(found.matches[2].status.find("not parallel"), std::string::npos)
      << found.matches[2].status;
}

}  // namespace
}  // namespace lidarcal::calibration
