// SPDX-License-Identifier: BSD-3-Clause
// Calibration against measured distances (Alhashimi et al. 2016 section 5): the known-distance
// readings of poles and walls, the fit with its stop-clustered standard errors, the noise exponent
// test, and the matching of reference entries to targets.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "calibration/reference.hpp"
#include "detectors/walls.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::calibration {
namespace {

simulation::LandmarkLevelConfig field(NoiseKind noise, double sigma_e) {
  simulation::LandmarkLevelConfig c;
  c.landmarks = {
      {1.5, 0.75, 0.12}, {0.3, 2.2, 0.12}, {2.4, 3.4, 0.12}, {3.9, -1.3, 0.12}, {0.9, -2.8, 0.12}};
  c.path.stops = 10;
  c.path.scans_per_stop = 10;
  c.path.sigma_s_m = 0.02;
  c.path.sigma_psi_rad = deg2rad(0.5);
  c.model.bias.alpha = {0.0525, 0.8838, 0.0584};
  c.model.noise.kind = noise;
  c.model.noise.sigma_e = sigma_e;
  c.model.range_min_m = 0.2;
  c.model.range_max_m = 6.0;
  c.sigma_theta_rad = deg2rad(0.2);
  c.beams = true;
  return c;
}

/// What a user with a tape would write: every visible pole's centre distance from the true
/// pose of each stop, with its bearing (so that the entry names one pole). A pole behind a
/// nearer one is left out: the landmark-level simulator does not occlude, a real sensor would.
Reference tapeMeasured(const simulation::LandmarkLevelConfig& c,
                       const simulation::LandmarkLevelSample& s) {
  Reference ref;
  for (std::size_t k = 0; k < s.stops.size(); ++k) {
    const Pose2& a = s.stops[k].actual;
    auto hidden = [&](const Cylinder& l) {
      const double dl = std::hypot(l.x_m - a.x_m, l.y_m - a.y_m),
                   bl = std::atan2(l.y_m - a.y_m, l.x_m - a.x_m);
      for (const auto& o : c.landmarks) {
        const double dox = o.x_m - a.x_m, doy = o.y_m - a.y_m, d = std::hypot(dox, doy);
        if (d < dl && std::abs(wrapAngle(std::atan2(doy, dox) - bl)) <
                          std::asin(o.radius_m / d) + std::asin(l.radius_m / dl))
          return true;
      }
      return false;
    };
    for (const auto& l : c.landmarks) {
      if (hidden(l)) continue;
      ReferenceDistance d;
      d.stop = k;
      d.distance_m = std::hypot(l.x_m - a.x_m, l.y_m - a.y_m);
      d.bearing_rad = wrapAngle(std::atan2(l.y_m - a.y_m, l.x_m - a.x_m) - a.yaw_rad);
      ref.distances.push_back(d);
    }
  }
  return ref;
}

double fStdErr(const CalibrationModel& m, double d) {
  const std::size_t n = m.model.bias.alpha.size();
  double v = 0.0, pi = 1.0;
  for (std::size_t i = 0; i < n; ++i, pi *= d) {
    double pj = 1.0;
    for (std::size_t j = 0; j < n; ++j, pj *= d) v += pi * m.alpha_covariance[i * n + j] * pj;
  }
  return std::sqrt(v);
}

TEST(ReferenceCalibration, RecoversTheBiasAndIts95PercentIntervalsCoverTheTruth) {
  // 40 independent recordings (seeds 101-140, not used to develop the estimator). The 95 %
  // interval of f(d) must contain the true f(d) in about 95 % of them: at least 34 of 40 (the
  // probability of 33 or fewer with a true 95 % coverage is about 1.5 %), and not all 40 at
  // every distance when the intervals would be far too wide (checked by the accuracy bound).
  const auto cfg = field(NoiseKind::squared, 0.0019176);
  const BiasPolynomial truth{cfg.model.bias.alpha};
  const std::vector<double> at = {1.0, 2.0, 3.0};
  std::vector<int> covered(at.size(), 0);
  int exponent_two = 0;
  const int seeds = 40;
  for (int seed = 101; seed < 101 + seeds; ++seed) {
    SCOPED_TRACE(seed);
    const auto sample = simulation::simulateLandmarkLevel(cfg, static_cast<std::uint64_t>(seed));
    const ReferenceReadings known = knownReadings(sample.obs, tapeMeasured(cfg, sample), 0.12);
    for (const auto& m : known.matches)
      ASSERT_TRUE(m.ok()) << "entry " << m.entry << ": " << m.status;
    const CalibrationModel m = calibrateWithReference(known.readings, CalibrationConfig{});
    ASSERT_STREQ(m.status.name(), "ok") << m.status.message;
    ASSERT_TRUE(m.fitted_range_m.has_value());
    exponent_two += m.noise_fits.exponent_best == 2;
    for (std::size_t i = 0; i < at.size(); ++i) {
      const double err = m.model.bias(at[i]) - truth(at[i]);
      EXPECT_LT(std::abs(err), 0.01) << "at " << at[i] << " m";  // the raw error there is 5-20 cm
      covered[i] += std::abs(err) <= 1.96 * fStdErr(m, at[i]);
    }
  }
  for (std::size_t i = 0; i < at.size(); ++i)
    EXPECT_GE(covered[i], 34) << "coverage at " << at[i] << " m";
  EXPECT_GE(exponent_two, 36)
      << "Alhashimi et al. 2016's test should name the squared law it was simulated with";
}

TEST(ReferenceCalibration, NoiseExponentTestNamesConstantNoiseOfATimeOfFlightSensor) {
  auto cfg = field(NoiseKind::constant, 0.004);
  cfg.model.bias.alpha = {0.01, 1.0};
  for (std::uint64_t seed = 201; seed <= 203; ++seed) {
    SCOPED_TRACE(seed);
    const auto sample = simulation::simulateLandmarkLevel(cfg, seed);
    const auto known = knownReadings(sample.obs, tapeMeasured(cfg, sample), 0.12);
    const CalibrationModel m = calibrateWithReference(known.readings, CalibrationConfig{});
    ASSERT_STREQ(m.status.name(), "ok") << m.status.message;
    EXPECT_EQ(m.noise_fits.exponent_best, 0);
    EXPECT_EQ(m.model.noise.kind, NoiseKind::constant);
    EXPECT_NEAR(m.model.noise.sigma_e, 0.004, 0.0008);
    EXPECT_NEAR(m.model.bias(2.0) - 2.0, 0.01, 0.003);
  }
}

TEST(ReferenceCalibration, MatchesEntriesByBearingOrByMeasuredDistance) {
  const auto cfg = field(NoiseKind::squared, 0.0019176);
  const auto sample = simulation::simulateLandmarkLevel(cfg, 7);
  const Pose2& a = sample.stops[2].actual;
  const auto& far_pole = cfg.landmarks[3];  // (3.9, -1.3): the farthest from stop 2
  ReferenceDistance by_distance;
  by_distance.stop = 2;
  by_distance.distance_m = std::hypot(far_pole.x_m - a.x_m, far_pole.y_m - a.y_m);
  ReferenceDistance wrong_bearing = by_distance;
  wrong_bearing.bearing_rad =
      wrapAngle(std::atan2(far_pole.y_m - a.y_m, far_pole.x_m - a.x_m) - a.yaw_rad + kPi);
  ReferenceDistance nothing_there = by_distance;
  nothing_there.distance_m = 9.0;
  Reference ref;
  ref.distances = {by_distance, wrong_bearing, nothing_there};
  const auto known = knownReadings(sample.obs, ref, 0.12);
  ASSERT_EQ(known.matches.size(), 3u);
  EXPECT_TRUE(known.matches[0].ok()) << known.matches[0].status;
  EXPECT_EQ(known.matches[0].landmark, 4);
  EXPECT_GT(known.matches[0].readings, 0u);
  // the failed entries give no readings
  for (const auto& r : known.readings) EXPECT_EQ(r.entry, 0u);
  EXPECT_FALSE(known.matches[1].ok());
  EXPECT_NE(known.matches[1].status.find("bearing"), std::string::npos) << known.matches[1].status;
  EXPECT_FALSE(known.matches[2].ok());
  EXPECT_NE(known.matches[2].status.find("stop 2"), std::string::npos) << known.matches[2].status;
}

/// Readings at twelve taped stops, 0.5-3.25 m, of a sensor whose mean reading is truth(d) with
/// 3 mm noise: readings(k) of them at stop k, each stop's tape off by its own 2 mm error (stated).
std::vector<KnownReading> tapedReadings(std::uint64_t seed, const BiasPolynomial& truth,
                                        int (*readings)(std::size_t)) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.003), tape(0.0, 0.002);
  std::vector<KnownReading> r;
  for (std::size_t k = 0; k < 12; ++k) {
    const double d = 0.5 + 0.25 * static_cast<double>(k), taped = d + tape(rng);
    for (int i = 0; i < readings(k); ++i)
      r.push_back({k, k, static_cast<std::size_t>(i), kUnknownBeam, taped, truth(d) + noise(rng),
                   0.0, 0.002});
  }
  return r;
}

TEST(ReferenceCalibration, WhereTheTapeErrorOutweighsTheNoiseEveryEntryCountsAboutAlike) {
  // Twelve taped distances, every other one with 100 times the readings. Each tape distance is
  // off by its own 2 mm error, which no number of readings averages away: weighting the entries
  // by their readings (the noise law alone) leans on half of them, the random-effects weights of
  // calibration/discrepancy.hpp on all. Over 40 seeds the latter's f must be closer to the truth
  // (for equal weights against 100:1 the expected squared error is about half).
  const BiasPolynomial truth{{0.02, 0.97, 0.012}};
  const int seeds = 40;
  double re_se = 0.0, law_se = 0.0;
  for (int seed = 301; seed < 301 + seeds; ++seed) {
    const std::vector<KnownReading> r = tapedReadings(
        static_cast<std::uint64_t>(seed), truth, [](std::size_t k) { return k % 2 ? 500 : 5; });
    CalibrationConfig config;
    config.max_order = 2;  // the truth's: the weights, not the order, are under test
    config.noise = NoiseKind::constant;
    const CalibrationModel m = calibrateWithReference(r, config);
    ASSERT_STREQ(m.status.name(), "ok") << m.status.message;
    std::vector<double> d, y;
    std::vector<std::size_t> stop;
    for (const auto& k : r) d.push_back(k.d_m), y.push_back(k.y_m), stop.push_back(k.stop);
    const BiasPolynomial law{fitClustered(d, y, stop, m.model.bias.order(), 0.0).alpha};
    for (double at = 0.5; at <= 3.25; at += 0.25) {
      re_se += std::pow(m.model.bias(at) - truth(at), 2);
      law_se += std::pow(law(at) - truth(at), 2);
    }
  }
  EXPECT_LT(re_se, 0.8 * law_se) << "RMS ratio " << std::sqrt(re_se / law_se);
}

TEST(ReferenceCalibration, AWrongTapeReadingIsNamedInAWarningAndCorrectOnesAreNot) {
  // Twelve taped stops on a sensor that follows a quadratic; in the second model the tape of
  // entry 5 was read 30 mm long (its readings then lie 30 mm short of what the others predict).
  const BiasPolynomial truth{{0.02, 0.97, 0.012}};
  int clean_warnings = 0, named = 0;
  const int seeds = 20;
  for (int seed = 401; seed < 401 + seeds; ++seed) {
    std::vector<KnownReading> r =
        tapedReadings(static_cast<std::uint64_t>(seed), truth, [](std::size_t) { return 50; });
    auto disagreeing = [](const CalibrationModel& m) {
      std::vector<std::string> w;
      for (const auto& s : m.warnings)
        if (s.find("disagrees with the other measured distances") != std::string::npos)
          w.push_back(s);
      return w;
    };
    CalibrationConfig config;
    config.noise = NoiseKind::constant;
    const CalibrationModel clean = calibrateWithReference(r, config);
    ASSERT_STREQ(clean.status.name(), "ok") << clean.status.message;
    clean_warnings += static_cast<int>(disagreeing(clean).size());
    for (auto& k : r)
      if (k.entry == 5) k.d_m += 0.030;
    const auto w = disagreeing(calibrateWithReference(r, config));
    named += w.size() == 1 && w[0].rfind("distances[5] (stop 5", 0) == 0 ? 1 : 0;
  }
  EXPECT_LE(clean_warnings, 2);  // Bonferroni at 5 %: about one in 20 fits
  EXPECT_EQ(named, seeds);
}

TEST(ReferenceCalibration, TooFewStopsIsAStatusNotAModel) {
  std::vector<KnownReading> r;
  for (std::size_t k = 0; k < 2; ++k)
    for (int i = 0; i < 50; ++i)
      r.push_back({k, k, 0, static_cast<std::uint32_t>(i), 1.0 + k, 1.01 + k});
  const CalibrationModel m = calibrateWithReference(r, CalibrationConfig{});
  EXPECT_STREQ(m.status.name(), "too_few_reference_stops");
  EXPECT_NE(m.status.message.find("3 or more stops"), std::string::npos);
}

TEST(ReferenceCalibration, WallReadingsHaveTheDistanceAlongTheBeamToTheMeasuredPlane) {
  // A wall 1.5 m from the sensor, its normal at 30 degrees; the sensor reads 2 % long.
  const double D = 1.5, normal = deg2rad(30.0);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  LandmarkObservations obs;
  obs.commanded = {Pose2{}};
  for (int j = -30; j <= 30; ++j) {
    const double a = normal + deg2rad(j);
    const double d = D / std::cos(a - normal), y = 1.02 * d;
    pcl::PointXYZI p;
    p.x = static_cast<float>(y * std::cos(a));
    p.y = static_cast<float>(y * std::sin(a));
    p.z = 0.0f;
    cloud.push_back(p);
  }
  const auto walls = detectors::findWalls(cloud, detectors::WallConfig{});
  ASSERT_EQ(walls.size(), 1u);
  EXPECT_NEAR(walls[0].distance_m, 1.02 * D, 1e-4);
  EXPECT_NEAR(walls[0].normal_rad, normal, 1e-4);
  WallSighting ws;
  ws.normal_rad = walls[0].normal_rad;
  ws.distance_m = walls[0].distance_m;
  for (const auto i : walls[0].inliers) {
    const auto& p = cloud[static_cast<std::size_t>(i)];
    ws.beams.push_back({std::atan2(double(p.y), double(p.x)), std::hypot(double(p.x), double(p.y)),
                        static_cast<std::uint32_t>(i)});
  }
  obs.walls = {ws};
  Reference ref;
  ReferenceDistance e;
  e.target = ReferenceTarget::wall;
  e.distance_m = D;
  ref.distances = {e};
  const auto known = knownReadings(obs, ref, 0.0);
  ASSERT_TRUE(known.matches[0].ok()) << known.matches[0].status;
  EXPECT_NEAR(known.matches[0].measured_m, 1.02 * D, 1e-4);
  ASSERT_GT(known.readings.size(), 40u);
  // the 2 % the sensor reads long
  for (const auto& r : known.readings) EXPECT_NEAR(r.y_m / r.d_m, 1.02, 1e-5);
}

}  // namespace
}  // namespace lidarcal::calibration
