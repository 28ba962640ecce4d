// SPDX-License-Identifier: BSD-3-Clause
// The simulator's effects (simulation/simulator.hpp), which the diagnosis' replicas and extended
// models simulate, against their definitions; their scene keys round-trip.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "calibration/joint_refinement.hpp"
#include "common/rng.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "io/scene_io.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

TEST(SimulatorEffects, EffectReadingMatchesTheDefinitionAtEveryIncidence) {
  // y = f(d) + b (1 - cos phi) + offset + c t + sigma(d) (1 / cos phi)^gamma e is linear in e:
  // the reading at e = 0 is the mean and y(e = 1) - y(e = 0) the standard deviation, exactly.
  // Several incidences, so that no single one can hide a wrong form (at cos phi = 0.5,
  // 1 - cos phi equals cos phi and 1 / cos phi - 1 equals 1).
  RangeModel m;
  m.bias.alpha = {0.05, 0.9, 0.05};
  m.noise.kind = NoiseKind::squared;
  m.noise.sigma_e = 0.002;
  std::mt19937_64 unused(1);
  const double d = 2.5;
  for (double b : {0.03, -0.02}) {
    for (double gamma : {1.0, 1.5}) {
      RangeEffects fx;
      fx.incidence_noise_exponent = gamma;
      fx.incidence_bias_m = b;
      fx.range_drift_m_per_scan = 1e-4;
      for (double cos_inc : {1.0, 0.95, 0.8, 0.5, 0.3, 0.1}) {
        SCOPED_TRACE(testing::Message()
                     << "b " << b << ", gamma " << gamma << ", cos phi " << cos_inc);
        const double mean = m.bias(d) + b * (1.0 - cos_inc) + 0.01 + 1e-4 * 100;
        const double y0 = simulation::effectReading(m, fx, d, {cos_inc, 0.01, 100}, 0.0, unused);
        const double y1 = simulation::effectReading(m, fx, d, {cos_inc, 0.01, 100}, 1.0, unused);
        EXPECT_NEAR(y0, mean, 1e-12);
        EXPECT_NEAR(y1 - y0, m.noise.stddev(d, m.bias) * std::pow(1.0 / cos_inc, gamma), 1e-12);
      }
      // Grazing beams are treated as at cos phi = 0.05 (87 degrees).
      EXPECT_NEAR(simulation::effectReading(m, fx, d, {0.01, 0.0, 0}, 0.0, unused),
                  m.bias(d) + b * 0.95, 1e-12);
    }
  }
  // The bias grows away from normal incidence (b > 0: longer readings at grazing incidence).
  RangeEffects fx;
  fx.incidence_bias_m = 0.03;
  EXPECT_GT(simulation::effectReading(m, fx, d, {0.2, 0.0, 0}, 0.0, unused),
            simulation::effectReading(m, fx, d, {0.9, 0.0, 0}, 0.0, unused));
  // The drift is zero at its reference scan and grows by c per scan from there (one convention
  // for the simulator and the fits: c (t - t_ref)).
  RangeEffects drift;
  drift.range_drift_m_per_scan = 2e-4;
  drift.range_drift_reference_scan = 40.0;
  EXPECT_NEAR(simulation::effectReading(m, drift, d, {1.0, 0.0, 40}, 0.0, unused), m.bias(d),
              1e-12);
  EXPECT_NEAR(simulation::effectReading(m, drift, d, {1.0, 0.0, 50}, 0.0, unused),
              m.bias(d) + 2e-4 * 10, 1e-12);
  EXPECT_NEAR(simulation::effectReading(m, drift, d, {1.0, 0.0, 0}, 0.0, unused),
              m.bias(d) - 2e-4 * 40, 1e-12);
  // Every effect off: exactly rangeReading().
  EXPECT_DOUBLE_EQ(simulation::effectReading(m, RangeEffects{}, d, {0.3, 0.0, 7}, 0.7, unused),
                   simulation::rangeReading(m, d, 0.7));
}

TEST(SimulatorEffects, StudentNoiseKeepsTheVarianceAndQuantisationTheGrid) {
  RangeModel m;
  m.noise.kind = NoiseKind::constant;
  m.noise.sigma_e = 0.01;
  RangeEffects fx;
  fx.noise_student_dof = 4.0;
  fx.range_resolution_m = 0.001;
  std::mt19937_64 rng(9), fxrng(10);
  std::normal_distribution<double> n(0.0, 1.0);
  constexpr int kN = 40000;
  double s2 = 0.0, s4 = 0.0;
  for (int i = 0; i < kN; ++i) {
    const double y = simulation::effectReading(m, fx, 2.0, {}, n(rng), fxrng);
    EXPECT_NEAR(y / 0.001, std::round(y / 0.001), 1e-6);
    s2 += (y - 2.0) * (y - 2.0) / kN;
    s4 += std::pow(y - 2.0, 4) / kN;
  }
  EXPECT_NEAR(s2 / (0.01 * 0.01), 1.0, 0.1);  // unit-variance t (quantisation adds 1/12 mm^2)
  EXPECT_GT(s4 / (s2 * s2), 4.0);             // heavier tails than a normal (kurtosis 3)
}

TEST(SimulatorEffects, MixedPixelsOnlyAtTheEdgesAndAtTheRequestedRate) {
  auto c = test::paperFieldLandmarkLevel();
  c.effects.mixed_pixel_fraction = 0.3;
  c.model.noise.sigma_e = 0.0;  // noise-free: a mixed reading is the only way to be off
  const auto s = simulation::simulateLandmarkLevel(c, 4);
  double edges = 0, mixed_edges = 0, inner_off = 0;
  for (std::size_t i = 0; i < s.obs.sightings.size(); ++i) {
    const auto& b = s.obs.sightings[i].beams;
    for (std::size_t j = 0; j < b.size(); ++j) {
      const bool off = std::abs(b[j].range_m - c.model.bias(s.true_range_m[i][j])) > 1e-9;
      if (j == 0 || j + 1 == b.size()) {
        edges += 1;
        mixed_edges += off;
      } else {
        inner_off += off;
      }
    }
  }
  EXPECT_EQ(inner_off, 0);
  EXPECT_NEAR(mixed_edges / edges, 0.3, 0.05);  // nearly every edge beam has a wall behind it here
}

TEST(SimulatorEffects, SceneKeysRoundTripAndStayAbsentWhenOff) {
  const auto file = std::filesystem::temp_directory_path() /
                    ("lidarcal-effects-" + std::to_string(::getpid()) + ".json");
  {
    std::ofstream out(file);
    out << R"({"sensor": {"range_min_m": 0.1, "range_max_m": 8,
                          "effects": {"incidence_noise_exponent": 1.5, "incidence_bias_m": 0.02,
                                      "range_drift_m_per_scan": 0.0001, "mixed_pixel_fraction": 0.05,
                                      "noise_student_dof": 4, "range_resolution_m": 0.001}},
               "path": {"step_error_fraction": 0.03},
               "landmarks": [{"x_m": 1, "y_m": 2, "radius_m": 0.1, "range_offset_m": 0.02}],
               "walls": [{"x0_m": 0, "y0_m": 5, "x1_m": 3, "y1_m": 5, "range_offset_m": -0.01}]})";
  }
  const Scene s = io::readScene(file);
  std::filesystem::remove(file);
  EXPECT_EQ(s.sensor.effects.incidence_noise_exponent, 1.5);
  EXPECT_EQ(s.sensor.effects.incidence_bias_m, 0.02);
  EXPECT_EQ(s.sensor.effects.range_drift_m_per_scan, 0.0001);
  EXPECT_EQ(s.sensor.effects.mixed_pixel_fraction, 0.05);
  EXPECT_EQ(s.sensor.effects.noise_student_dof, 4.0);
  EXPECT_EQ(s.sensor.effects.range_resolution_m, 0.001);
  EXPECT_EQ(s.path.step_error_fraction, 0.03);
  EXPECT_EQ(s.landmarks[0].range_offset_m, 0.02);
  EXPECT_EQ(s.walls[0].range_offset_m, -0.01);
  const auto j = io::sceneToJson(s);
  EXPECT_EQ(j["sensor"]["effects"]["noise_student_dof"], 4.0);
  EXPECT_EQ(j["walls"][0]["range_offset_m"], -0.01);
  Scene off = s;
  off.sensor.effects = RangeEffects{};
  off.path.step_error_fraction = 0.0;
  off.landmarks[0].range_offset_m = 0.0;
  const auto k = io::sceneToJson(off);
  EXPECT_FALSE(k["sensor"].contains("effects"));
  EXPECT_FALSE(k["path"].contains("step_error_fraction"));
  EXPECT_FALSE(k["landmarks"][0].contains("range_offset_m"));
}

TEST(SimulatorEffects, StepErrorScalesTheTruePath) {
  Scene s;
  s.path.stops = 5;
  s.path.step_m = 0.4;
  s.path.step_error_fraction = 0.05;
  const auto stops = simulation::planStops(s, 1);
  for (std::size_t k = 0; k < stops.size(); ++k)
    EXPECT_NEAR(stops[k].actual.x_m, 0.42 * static_cast<double>(k), 1e-12);
}

}  // namespace
}  // namespace lidarcal::diagnosis
