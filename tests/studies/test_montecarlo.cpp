// SPDX-License-Identifier: BSD-3-Clause
// Monte Carlo study (Alhashimi et al. 2021 Figs. 7-11): layouts keep their constraints, per-stop
// averaging is exact, quartiles follow their definition, the study is deterministic whatever the
// thread count, and a tiny study's statistics agree with a direct computation done here from the
// simulator and the estimators.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include <gtest/gtest.h>

#include "calibration/calibrate.hpp"
#include "calibration/inversion.hpp"
#include "common/rng.hpp"
#include "simulation/landmark_level.hpp"
#include "studies/draw.hpp"
#include "studies/placement.hpp"
#include "studies/runner.hpp"
#include "studies/statistics.hpp"
#include "studies/study.hpp"

namespace lidarcal::studies {
namespace {

TEST(Placement, EveryLayoutKeepsItsConstraintsAndLayoutsAreNested) {
  const PathSpec path = TrialConfig::defaultPath();
  const PlacementConfig cfg;
  std::vector<Pose2> stops;
  for (int k = 0; k < path.stops; ++k) stops.push_back(commandedPose(path, k));
  int nested = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE(seed);
    auto rng = makeRng(seed, 0);
    const auto big = placeLandmarks(path, 8, cfg, rng);
    ASSERT_EQ(big.size(), 8u);
    for (std::size_t i = 0; i < big.size(); ++i) {
      for (const Pose2& p : stops) {
        const double d = std::hypot(big[i].x_m - p.x_m, big[i].y_m - p.y_m) - big[i].radius_m;
        EXPECT_GE(d, cfg.min_surface_m);
        EXPECT_LE(d, cfg.max_surface_m);
      }
      EXPECT_GE(std::abs(big[i].y_m - path.start.y_m), cfg.min_lateral_m);
      for (std::size_t j = 0; j < i; ++j)
        EXPECT_GE(std::hypot(big[i].x_m - big[j].x_m, big[i].y_m - big[j].y_m),
                  2 * cfg.radius_m + cfg.min_separation_m);
    }
    // The first L landmarks of a layout of 8 are the layout of L drawn from the same stream,
    // unless the layout of 8 had to be drawn again (rare: 4 in 1000 trials of the default study).
    auto rng3 = makeRng(seed, 0);
    const auto small = placeLandmarks(path, 3, cfg, rng3);
    bool same = true;
    for (std::size_t i = 0; i < small.size(); ++i)
      same = same && small[i].x_m == big[i].x_m && small[i].y_m == big[i].y_m;
    nested += same;
  }
  EXPECT_GE(nested, 18);
}

TEST(Placement, ImpossibleRegionThrows) {
  PlacementConfig cfg;
  cfg.max_surface_m = 0.4;  // no point is within 0.4 m of every stop of a 2.85 m path
  cfg.max_attempts = 100;
  cfg.max_restarts = 2;
  auto rng = makeRng(1, 0);
  EXPECT_THROW(placeLandmarks(TrialConfig::defaultPath(), 1, cfg, rng), std::runtime_error);
}

TEST(AverageScans, EachBeamIsTheMeanOfItsReadingsAtTheStop) {
  simulation::LandmarkLevelConfig cfg;
  cfg.landmarks = {{1.0, 1.0, 0.12}, {2.0, -1.5, 0.12}};
  cfg.path.stops = 4;
  cfg.path.scans_per_stop = 5;
  cfg.model = TrialConfig::paperSensor();
  cfg.sigma_theta_rad = 0.01;
  cfg.beams = true;
  const auto sample = simulation::simulateLandmarkLevel(cfg, 3);
  const LandmarkObservations avg = averageScans(sample.obs);
  std::map<std::tuple<std::size_t, int, std::uint32_t>, std::pair<double, int>> direct;
  for (const auto& s : sample.obs.sightings)
    for (const auto& b : s.beams) {
      auto& a = direct[{s.stop, s.landmark, b.beam}];
      a.first += b.range_m;
      ++a.second;
    }
  std::size_t beams = 0;
  for (const auto& s : avg.sightings) {
    for (const auto& b : s.beams) {
      const auto& a = direct.at({s.stop, s.landmark, b.beam});
      EXPECT_NEAR(b.range_m, a.first / a.second, 1e-12);
      ++beams;
    }
  }
  EXPECT_EQ(beams, direct.size());
  EXPECT_EQ(avg.sightings.size(), 4u * 2u);  // one per (stop, landmark)
  EXPECT_EQ(avg.commanded.size(), sample.obs.commanded.size());
}

TEST(Quartiles, FollowTheType7Definition) {
  // 1..5: order statistics exactly; 1..4: interpolated (R: quantile(1:4) = 1.75, 2.5, 3.25).
  auto q = quartiles({5, 1, 4, 2, 3});
  EXPECT_DOUBLE_EQ(q.q25, 2.0);
  EXPECT_DOUBLE_EQ(q.median, 3.0);
  EXPECT_DOUBLE_EQ(q.q75, 4.0);
  q = quartiles({4, 3, 2, 1, std::nan("")});  // non-finite values are dropped
  EXPECT_DOUBLE_EQ(q.q25, 1.75);
  EXPECT_DOUBLE_EQ(q.median, 2.5);
  EXPECT_DOUBLE_EQ(q.q75, 3.25);
  EXPECT_TRUE(std::isnan(quartiles({}).median));
}

/// A small, fast configuration: 8 stops, 3 scans per stop.
TrialConfig smallConfig() {
  TrialConfig c;
  c.path.stops = 8;
  c.path.step_m = 0.3;
  c.path.scans_per_stop = 3;
  return c;
}

TEST(Study, OutputIsTheSameWithOneAndTwoThreads) {
  StudyGrids g;
  g.sigma_s_m = {0.003, 0.03};
  g.sigma_theta_deg = {1.0};
  g.fig9_landmarks = {2};
  RunOptions o;
  o.trials = 6;
  o.joint_trials = 2;
  o.seed = 7;
  o.threads = 1;
  const auto one = runStudy({Figure::fig9, Figure::fig10}, g, smallConfig(), o);
  o.threads = 2;
  const auto two = runStudy({Figure::fig9, Figure::fig10}, g, smallConfig(), o);
  ASSERT_FALSE(one.interrupted);
  ASSERT_EQ(one.files.size(), two.files.size());
  for (std::size_t i = 0; i < one.files.size(); ++i) {
    SCOPED_TRACE(one.files[i].first);
    EXPECT_EQ(one.files[i].first, two.files[i].first);
    EXPECT_EQ(one.files[i].second, two.files[i].second);
  }
  // A different seed gives different numbers (the CSV depends on the seed at all).
  o.seed = 8;
  const auto other = runStudy({Figure::fig9, Figure::fig10}, g, smallConfig(), o);
  EXPECT_NE(one.files[0].second, other.files[0].second);
}

TEST(Study, AStopRequestInterruptsAndProducesNoFiles) {
  std::atomic<bool> stop{true};
  RunOptions o;
  o.trials = 50;
  o.stop = &stop;
  StudyGrids g;
  g.sigma_s_m = {0.01};
  g.sigma_theta_deg = {1.0};
  const auto out = runStudy({Figure::fig10}, g, smallConfig(), o);
  EXPECT_TRUE(out.interrupted);
  EXPECT_TRUE(out.files.empty());
}

// ------------------------------------------------------------------ direct computation

/// CSV row of a one-cell figure as column name -> value.
std::map<std::string, double> csvRow(const std::string& csv) {
  std::istringstream in(csv);
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  std::vector<std::string> names, values;
  for (std::istringstream h(header); std::getline(h, names.emplace_back(), ',');) {
  }
  for (std::istringstream r(row); std::getline(r, values.emplace_back(), ',');) {
  }
  std::map<std::string, double> out;
  for (std::size_t i = 0; i < std::min(names.size(), values.size()); ++i)
    if (!names[i].empty())
      out[names[i]] = values[i] == "NaN" ? std::nan("") : std::atof(values[i].c_str());
  return out;
}

/// Eq. 31 computed here: MSE of raw over MSE of corrected readings (LS inversion).
double mseRatio(const RangeModel& model, const std::vector<double>& truth,
                const std::vector<double>& raw) {
  const calibration::RangeInverter inv(
      model, calibration::inversionWindow(model, calibration::InversionMethod::ls));
  double a = 0.0, b = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const auto c = inv.invert(raw[i]);
    const double corrected = c ? *c : raw[i];
    a += (raw[i] - truth[i]) * (raw[i] - truth[i]);
    b += (corrected - truth[i]) * (corrected - truth[i]);
  }
  return a / b;
}

/// What the direct computation finds over the trials of one cell.
struct DirectResults {
  std::vector<double> cf_ratio, oracle_ratio, cf_single;  ///< Eq. 31's MSE ratios, per trial
  std::vector<double> radial, tangential;  ///< triangulated centres' errors, per (trial, landmark)
  std::map<int, int> cf_orders;            ///< the closed form's AIC order -> trials
};

/// A test set's true distances and raw readings: averaged per (stop, landmark, beam), and the
/// single central readings.
struct TestReadings {
  std::vector<double> truth, raw, single_truth, single_raw;
};

/// The beam closest to the sighting's bearing: without bearing noise, the central beam.
std::size_t centralBeam(const Sighting& s) {
  std::size_t best = 0;
  for (std::size_t j = 1; j < s.beams.size(); ++j)
    if (std::abs(wrapAngle(s.beams[j].angle_rad - s.bearing_rad)) <
        std::abs(wrapAngle(s.beams[best].angle_rad - s.bearing_rad)))
      best = j;
  return best;
}

TestReadings testReadings(const simulation::LandmarkLevelSample& test) {
  std::map<std::tuple<std::size_t, int, std::uint32_t>, std::array<double, 3>> groups;
  TestReadings r;
  for (std::size_t i = 0; i < test.obs.sightings.size(); ++i) {
    const Sighting& s = test.obs.sightings[i];
    for (std::size_t j = 0; j < s.beams.size(); ++j) {
      auto& a = groups[{s.stop, s.landmark, s.beams[j].beam}];
      a[0] += test.true_range_m[i][j];
      a[1] += s.beams[j].range_m;
      a[2] += 1.0;
    }
    const std::size_t best = centralBeam(s);
    r.single_truth.push_back(test.true_range_m[i][best]);
    r.single_raw.push_back(s.beams[best].range_m);
  }
  for (const auto& [k, a] : groups) {
    r.truth.push_back(a[0] / a[2]);
    r.raw.push_back(a[1] / a[2]);
  }
  return r;
}

/// The oracle: central readings with their true distances, averaged per (landmark, stop, third
/// of the scans).
CalibrationModel oracleFit(const simulation::LandmarkLevelSample& calib,
                           const calibration::CalibrationConfig& cc) {
  std::map<std::tuple<int, std::size_t, int>, std::array<double, 3>> og;
  for (std::size_t i = 0; i < calib.obs.sightings.size(); ++i) {
    const Sighting& s = calib.obs.sightings[i];
    const std::size_t best = centralBeam(s);
    // 3 scans per stop: scan position in its stop
    const int part = static_cast<int>((s.scan - s.stop * 3) % 3);
    auto& a = og[{s.landmark, s.stop, part}];
    a[0] += calib.true_range_m[i][best];
    a[1] += s.beams[best].range_m;
    a[2] += 1.0;
  }
  std::vector<calibration::RangePair> pairs;
  for (const auto& [k, a] : og) pairs.push_back({a[0] / a[2], a[1] / a[2], std::get<2>(k)});
  return calibration::calibrateAgainstTruth(pairs, cc, {}, calib.obs.range_min_m,
                                            calib.obs.range_max_m);
}

/// Triangulated centres against the layout, in each landmark's radial/tangential frame.
void addCentreErrors(const CalibrationModel& cf, const simulation::LandmarkLevelSample& calib,
                     const std::vector<Cylinder>& layout, DirectResults& r) {
  double mx = 0.0, my = 0.0;
  for (const Pose2& p : calib.obs.commanded) {
    mx += p.x_m / static_cast<double>(calib.obs.commanded.size());
    my += p.y_m / static_cast<double>(calib.obs.commanded.size());
  }
  for (const auto& l : cf.landmarks) {
    const Cylinder& c = layout.at(static_cast<std::size_t>(l.id - 1));
    const double ux = c.x_m - mx, uy = c.y_m - my, n = std::hypot(ux, uy);
    r.radial.push_back(((l.x_m - c.x_m) * ux + (l.y_m - c.y_m) * uy) / n);
    r.tangential.push_back((-(l.x_m - c.x_m) * uy + (l.y_m - c.y_m) * ux) / n);
  }
}

/// The closed-form calibration the direct computation runs on each trial of the cell.
calibration::CalibrationConfig closedFormConfig() {
  calibration::CalibrationConfig cc;
  cc.max_order = 3;
  cc.noise = NoiseKind::polynomial;
  cc.closed_form_rule = calibration::OrderRule::aic;
  cc.method = calibration::Method::closed_form;
  cc.triangulation.sigma_s_m = 0.01;
  cc.triangulation.sigma_theta_rad = deg2rad(0.1);  // the study's floor for a zero sigma_theta
  return cc;
}

/// The study's CSV row against the direct computation over its 5 trials.
void expectTheRowAgrees(const std::map<std::string, double>& row, const DirectResults& r) {
  auto q = [](std::vector<double> v, int i) {
    std::sort(v.begin(), v.end());
    return v.at(static_cast<std::size_t>(i));
  };
  const double tol = 1e-5;  // the CSV holds 6 significant digits
  auto near = [&](double expected, const std::string& column) {
    SCOPED_TRACE(column);
    ASSERT_TRUE(row.count(column));
    EXPECT_NEAR(row.at(column), expected, tol * std::abs(expected) + 1e-12);
  };
  near(q(r.cf_ratio, 1), "closed_form_ratio_q25");
  near(q(r.cf_ratio, 2), "closed_form_ratio_median");
  near(q(r.cf_ratio, 3), "closed_form_ratio_q75");
  near(q(r.cf_single, 2), "closed_form_ratio1_median");
  near(q(r.oracle_ratio, 1), "oracle_ratio_q25");
  near(q(r.oracle_ratio, 2), "oracle_ratio_median");
  near(q(r.oracle_ratio, 3), "oracle_ratio_q75");
  for (int n = 0; n <= 3; ++n) {
    const int trials = r.cf_orders.count(n) ? r.cf_orders.at(n) : 0;
    near(trials / 5.0, "closed_form_order" + std::to_string(n) + "_rate");
  }
  EXPECT_EQ(row.at("joint_runs"), 0.0);
  // Bias and variance over the 10 (trial, landmark) samples.
  const std::vector<double>& radial = r.radial;
  const std::vector<double>& tangential = r.tangential;
  double mr = 0.0, mt = 0.0;
  for (std::size_t i = 0; i < radial.size(); ++i) {
    mr += radial[i] / static_cast<double>(radial.size());
    mt += tangential[i] / static_cast<double>(radial.size());
  }
  double var = 0.0;
  for (std::size_t i = 0; i < radial.size(); ++i)
    var += (std::pow(radial[i] - mr, 2) + std::pow(tangential[i] - mt, 2)) / (radial.size() - 1.0);
  near(static_cast<double>(radial.size()), "pos_triangulation_samples");
  near(std::hypot(mr, mt), "pos_triangulation_bias_m");
  near(var, "pos_triangulation_variance_m2");
}

TEST(Study, TinyStudyStatisticsAgreeWithADirectComputation) {
  // One cell, 5 trials (quartiles are then order statistics 2, 3 and 4), no bearing noise (so
  // a draw is exactly simulateLandmarkLevel's output), closed form and oracle.
  const TrialConfig config = smallConfig();
  const Cell cell{2, 0.01, 0.0};
  const std::uint64_t seed = 11;
  const std::size_t trials = 5;
  StudyGrids g;
  g.sigma_s_m = {cell.sigma_s_m};
  g.sigma_theta_deg = {0.0};
  g.fig10_landmarks = cell.landmarks;
  RunOptions o;
  o.trials = trials;
  o.joint_trials = 0;
  o.seed = seed;
  o.threads = 2;
  const auto out = runStudy({Figure::fig10}, g, config, o);
  ASSERT_FALSE(out.interrupted);
  const auto row = csvRow(out.files.at(0).second);

  const calibration::CalibrationConfig cc = closedFormConfig();
  DirectResults r;
  for (std::size_t t = 0; t < trials; ++t) {
    SCOPED_TRACE(t);
    const auto layout = trialLayout(config, seed, t, cell.landmarks);
    simulation::LandmarkLevelConfig sim;
    sim.landmarks = layout;
    sim.path = config.path;
    sim.path.sigma_s_m = cell.sigma_s_m;
    sim.model = config.sensor;
    sim.beams = true;
    const std::uint64_t ts = trialSeed(seed, cell, t);
    const auto calib = simulation::simulateLandmarkLevel(sim, deriveSeed(ts, 0));
    const TestReadings test =
        testReadings(simulation::simulateLandmarkLevel(sim, deriveSeed(ts, 1)));

    CalibrationModel cf = calibration::calibrate(calib.obs, cc);
    ASSERT_STREQ(cf.status.name(), "ok") << cf.status.message;
    cf.model.range_min_m = calib.obs.range_min_m;
    cf.model.range_max_m = calib.obs.range_max_m;
    r.cf_ratio.push_back(mseRatio(cf.model, test.truth, test.raw));
    r.cf_single.push_back(mseRatio(cf.model, test.single_truth, test.single_raw));
    ++r.cf_orders[cf.order_aic];

    CalibrationModel orc = oracleFit(calib, cc);
    ASSERT_STREQ(orc.status.name(), "ok") << orc.status.message;
    orc.model.range_min_m = calib.obs.range_min_m;
    orc.model.range_max_m = calib.obs.range_max_m;
    r.oracle_ratio.push_back(mseRatio(orc.model, test.truth, test.raw));
    addCentreErrors(cf, calib, layout, r);
  }
  expectTheRowAgrees(row, r);
}

// ------------------------------------------------------------------ what each estimator sees

TEST(AngleNoise, EachModePerturbsWhatItSaysAndNothingElse) {
  const TrialConfig config;
  const auto layout = trialLayout(config, 4, 0, 3);
  PathSpec path = config.path;
  path.sigma_s_m = 0.01;
  const double sigma = deg2rad(2.0);
  const Draw exact = drawLandmarkLevel(layout, path, config.sensor, 0.0, 9, false);
  // bearing: the centre bearings move, every beam (angle and reading) stays as without noise,
  // so the joint refinement, which fits the beams, cannot see sigma_theta.
  const Draw bearing = drawLandmarkLevel(layout, path, config.sensor, sigma, 9, false);
  // beams: each sighting's beams turn by the same angle as its centre bearing.
  const Draw beams = drawLandmarkLevel(layout, path, config.sensor, sigma, 9, true);
  ASSERT_EQ(exact.obs.sightings.size(), bearing.obs.sightings.size());
  ASSERT_EQ(exact.obs.sightings.size(), beams.obs.sightings.size());
  double bearing_ss = 0.0;
  for (std::size_t i = 0; i < exact.obs.sightings.size(); ++i) {
    const Sighting &e = exact.obs.sightings[i], &a = bearing.obs.sightings[i],
                   &b = beams.obs.sightings[i];
    const double v = wrapAngle(b.bearing_rad - e.bearing_rad);
    EXPECT_NEAR(wrapAngle(a.bearing_rad - e.bearing_rad), v, 1e-12);
    bearing_ss += v * v;
    ASSERT_EQ(e.beams.size(), a.beams.size());
    ASSERT_EQ(e.beams.size(), b.beams.size());
    for (std::size_t j = 0; j < e.beams.size(); ++j) {
      EXPECT_EQ(a.beams[j].angle_rad, e.beams[j].angle_rad);
      EXPECT_EQ(a.beams[j].range_m, e.beams[j].range_m);
      EXPECT_NEAR(wrapAngle(b.beams[j].angle_rad - e.beams[j].angle_rad), v, 1e-12);
      EXPECT_EQ(b.beams[j].range_m, e.beams[j].range_m);
    }
  }
  // One v per (stop, landmark), the same in the stop's 10 scans, drawn with sigma_theta: 60
  // draws, chi-square with 60 degrees of freedom, within 4 standard deviations of 60.
  EXPECT_NEAR(bearing_ss / (config.path.scans_per_stop * sigma * sigma), 60.0,
              4.0 * std::sqrt(120.0));
  // heading: every bearing of a stop is off by the same angle, minus the stop's heading error
  // (the sensor turned with the robot); seen from the true position with the commanded heading.
  path.sigma_psi_rad = sigma;
  const Draw heading = drawLandmarkLevel(layout, path, config.sensor, 0.0, 9, false);
  std::map<std::size_t, std::vector<double>> errors;
  for (const Sighting& s : heading.obs.sightings) {
    const Pose2& p = heading.actual[s.stop];
    const Cylinder& c = layout[static_cast<std::size_t>(s.landmark - 1)];
    const double truth =
        std::atan2(c.y_m - p.y_m, c.x_m - p.x_m) - heading.obs.commanded[s.stop].yaw_rad;
    errors[s.stop].push_back(wrapAngle(s.bearing_rad - truth));
  }
  double psi_ss = 0.0;
  for (const auto& [stop, e] : errors) {
    for (double x : e) EXPECT_NEAR(x, e.front(), 1e-12) << "stop " << stop;
    EXPECT_NEAR(-e.front(),
                wrapAngle(heading.actual[stop].yaw_rad - heading.obs.commanded[stop].yaw_rad),
                1e-12);
    psi_ss += e.front() * e.front();
  }
  EXPECT_NEAR(psi_ss / (sigma * sigma), 20.0, 4.0 * std::sqrt(40.0));  // 20 stops
}

TEST(AngleNoise, TheJointRefinementHardlySeesTheBearingModeAndSeesTheOthers) {
  // The old default: sigma_theta on the centre bearings only. From 0.5 to 5 degrees the closed
  // form's ratio falls; the joint refinement's input beams do not change (only its start, from the
  // closed form, does), so its ratio stays within its convergence tolerance. In the heading mode
  // (the default) and the beams mode it sees the noise. Same layouts and draws for both cells.
  TrialConfig c;  // the study's path: 20 stops, 10 scans per stop
  const Cell quiet{3, 0.01, deg2rad(0.5)}, noisy{3, 0.01, deg2rad(5.0)};
  const auto joint = static_cast<std::size_t>(Estimator::joint),
             cf = static_cast<std::size_t>(Estimator::closed_form);
  for (AngleNoise mode : {AngleNoise::bearing, AngleNoise::heading, AngleNoise::beams}) {
    c.angle_noise = mode;
    double joint_change = 0.0, cf_change = 0.0;
    int joint_steady = 0;  // trials whose joint ratio moves by less than 3 %
    for (std::size_t t = 0; t < 4; ++t) {
      const auto layout = trialLayout(c, 6, t, 3);
      const std::uint64_t seed = 1000 + t;
      const TrialResult a = runTrial(c, quiet, layout, seed, true),
                        b = runTrial(c, noisy, layout, seed, true);
      ASSERT_TRUE(a.estimators[joint].ok && b.estimators[joint].ok)
          << toString(mode) << ", trial " << t;
      const double jc = std::abs(std::log(b.estimators[joint].rules[0].mse_ratio[0] /
                                          a.estimators[joint].rules[0].mse_ratio[0]));
      joint_change += jc / 4.0;
      joint_steady += jc < 0.03;
      std::printf("%s trial %zu: joint |ln change| %.4f\n", toString(mode), t, jc);
      cf_change += std::abs(std::log(b.estimators[cf].rules[0].mse_ratio[0] /
                                     a.estimators[cf].rules[0].mse_ratio[0])) /
                   4.0;
    }
    SCOPED_TRACE(toString(mode));
    // Mean |ln(ratio at 5 degrees / ratio at 0.5 degree)| over 4 trials (measured: closed form
    // 2.2-3.3 in every mode; joint 0.007 bearing, 0.11 heading, 2.1 beams).
    EXPECT_GT(cf_change, 1.0);  // the closed form loses more than a factor e in every mode
    if (mode == AngleNoise::bearing) {
      // Its input beams are the same; only its start (from the closed form) moves. (Broken once
      // by the continuous-motion rule taking the per-stop averages for a robot that never stops.)
      EXPECT_EQ(joint_steady, 4);
      EXPECT_LT(joint_change, 0.03);
    } else if (mode == AngleNoise::heading) {
      EXPECT_GT(joint_change, 0.05);  // it estimates one heading per stop, shared by the landmarks
    } else {
      EXPECT_GT(joint_change, 1.0);  // beams: no term of its model absorbs eq. 5
    }
  }
}

// ------------------------------------------------------------------ the ratio against the sensor
// model

/// Eq. 31 expected for a perfect calibration on the `centre` test set of a layout, computed from
/// the sensor model alone: each (landmark, stop) reading averaged over K scans has mean f(d) and
/// variance sigma(d)^2 / K; inverting the true f leaves an error of variance sigma^2 / (K f'^2).
double expectedCeiling(const std::vector<Cylinder>& layout, const PathSpec& path,
                       const RangeModel& sensor) {
  const double K = path.scans_per_stop;
  double raw = 0.0, corrected = 0.0;
  for (const Cylinder& c : layout)
    for (int k = 0; k < path.stops; ++k) {
      const Pose2 p = commandedPose(path, k);
      const double d = std::hypot(c.x_m - p.x_m, c.y_m - p.y_m) - c.radius_m;
      const double bias = sensor.bias(d) - d, sigma = sensor.noise.stddev(d, sensor.bias);
      const auto& a = sensor.bias.alpha;
      const double slope = a[1] + 2.0 * a[2] * d;
      raw += bias * bias + sigma * sigma / K;
      corrected += sigma * sigma / (K * slope * slope);
    }
  return raw / corrected;
}

/// 40 trials of the closed form and the oracle (no joint refinement) from `seed`.
RunOptions fig9Options(std::uint64_t seed) {
  RunOptions o;
  o.trials = 40;
  o.joint_trials = 0;
  o.seed = seed;
  o.threads = 2;
  return o;
}

/// Fig. 9 of the paper's setting with five landmarks, over the given noise grid.
auto fig9AtFiveLandmarks(const TrialConfig& config, std::vector<double> sigma_s_m,
                         std::vector<double> sigma_theta_deg, const RunOptions& o) {
  StudyGrids g;
  g.fig9_landmarks = {5};
  g.sigma_s_m = std::move(sigma_s_m);
  g.sigma_theta_deg = std::move(sigma_theta_deg);
  return runStudy({Figure::fig9}, g, config, o);
}

TEST(Study, TheCeilingIsTheSensorModelsAndTheOracleComesCloseToIt) {
  // One cell of Fig. 9 in the paper's setting (L = 5, 20 stops, 10 scans per stop), closed form and
  // oracle. The ceiling (eq. 31 with the simulated sensor's own bias) agrees with the value the
  // sensor model gives for each layout, and the estimators stay at or below it.
  const TrialConfig config;
  const RunOptions o = fig9Options(3);
  const auto out = fig9AtFiveLandmarks(config, {0.01}, {1.0}, o);
  ASSERT_FALSE(out.interrupted);
  const auto row = csvRow(out.files.at(0).second);
  double expected = 0.0;
  for (std::size_t t = 0; t < o.trials; ++t)
    expected += expectedCeiling(trialLayout(config, o.seed, t, 5), config.path, config.sensor);
  expected /= static_cast<double>(o.trials);
  // Mean over 40 trials: each ratio scatters by about 15 % (its denominator is a sum of about 100
  // scaled chi-squares), so the mean by 2.5 %; the model ignores sigma_s (1 cm) and the curvature
  // of the inversion (below 1 %). Allow 10 %.
  EXPECT_NEAR(row.at("ceiling_ratioc_mean"), expected, 0.10 * expected);
  // Told the true distances, the oracle fits the bias from 300 averaged pairs: the error of three
  // coefficients fitted from 300 pairs adds about 3/300 of the readings' variance per pair to a
  // test reading's 1/10, so it should reach about 90 % of the ceiling (measured 95-98 %); allow
  // 80 %. No estimator beats the ceiling in the median.
  for (const char* set : {"ratio", "ratioc"}) {
    SCOPED_TRACE(set);
    const double ceiling = row.at(std::string("ceiling_") + set + "_median");
    EXPECT_GT(row.at(std::string("oracle_") + set + "_median"), 0.8 * ceiling);
    EXPECT_LE(row.at(std::string("oracle_") + set + "_median"), ceiling);
    EXPECT_LE(row.at(std::string("closed_form_") + set + "_median"),
              row.at(std::string("oracle_") + set + "_median"));
  }
}

/// Every data row of a study CSV, by column name.
std::vector<std::map<std::string, double>> csvRows(const std::string& csv) {
  std::istringstream in(csv);
  std::string header, line;
  std::getline(in, header);
  std::vector<std::map<std::string, double>> rows;
  while (std::getline(in, line))
    if (!line.empty()) rows.push_back(csvRow(header + "\n" + line));
  return rows;
}

TEST(Study, Fig9ClaimsHoldWhereWeReproduceThemAndFailWhereWeDoNot) {
  // Alhashimi et al. 2021 on Fig. 9: raising sigma_theta and sigma_s "does not lead to abrupt
  // decays". In sigma_s this holds for the closed form (docs/results/montecarlo.md, L = 5,
  // sigma_theta 1 deg: 16.3 at 0.1 cm, 11.9 at 3 cm); in sigma_theta it does not (about 1 at 5 deg:
  // the calibration no longer helps). Both are asserted, so that a change either way is seen; and
  // at low noise the closed form reaches most of what the true model can (14.7 of 21.9 at 1 cm, 1
  // deg).
  const auto out = fig9AtFiveLandmarks(TrialConfig{}, {0.001, 0.03}, {1.0, 5.0}, fig9Options(11));
  ASSERT_FALSE(out.interrupted);
  std::map<std::pair<double, double>, std::map<std::string, double>> cell;
  for (const auto& row : csvRows(out.files.at(0).second))
    cell[{row.at("sigma_s_m"), row.at("sigma_theta_deg")}] = row;
  ASSERT_EQ(cell.size(), 4u);
  auto closedForm = [&](double ss, double st) {
    return cell.at({ss, st}).at("closed_form_ratio_median");
  };
  auto ceiling = [&](double ss, double st) { return cell.at({ss, st}).at("ceiling_ratio_median"); };
  // A median over 40 trials scatters by about 3 %; the bounds sit well outside that.
  EXPECT_GT(closedForm(0.001, 1.0), 0.5 * ceiling(0.001, 1.0));
  EXPECT_GT(closedForm(0.03, 1.0), 0.5 * closedForm(0.001, 1.0)) << "gradual in sigma_s";
  EXPECT_LT(closedForm(0.001, 5.0), 3.0) << "the closed form's fall in sigma_theta";
  EXPECT_GT(ceiling(0.001, 5.0), 15.0) << "which the true model does not share";
}

TEST(ScanLevel, OneTrialFindsTheLandmarksAndCalibrates) {
  TrialConfig c = smallConfig();
  c.level = Level::scan;
  c.angle_noise = AngleNoise::heading;
  c.noise_scale = 0.2;  // the detector needs less noise than the paper's
  const Cell cell{3, 0.005, deg2rad(0.2)};
  for (std::size_t t = 0; t < 2; ++t) {
    SCOPED_TRACE(t);
    const auto layout = trialLayout(c, 5, t, cell.landmarks);
    const TrialResult r = runTrial(c, cell, layout, trialSeed(5, cell, t), true);
    EXPECT_EQ(r.detected_landmarks, 3);
    const double ceiling = r.ceiling[static_cast<std::size_t>(TestSet::beams)];
    for (const auto& e : r.estimators) {
      EXPECT_TRUE(e.ran);
      EXPECT_TRUE(e.ok);
      for (const auto& rule : e.rules) {
        // No estimator beats the true model by more than chance, and calibrating helps.
        EXPECT_LT(rule.mse_ratio[0], 1.2 * ceiling);
        EXPECT_GT(rule.mse_ratio[0], 1.0);
      }
    }
    // The oracle fits three coefficients from 72 pairs of single readings (8 stops, 3 landmarks,
    // 3 parts): their error adds about 3/72 of a reading's variance to a test reading's 1/3, so it
    // reaches about 90 % of the ceiling; allow half.
    for (const auto& rule : r.estimators[static_cast<std::size_t>(Estimator::oracle)].rules)
      EXPECT_GT(rule.mse_ratio[0], 0.5 * ceiling);
    // Every matched landmark is placed within 10 cm by the triangulation.
    for (const auto& e : r.estimators[0].landmarks)
      EXPECT_LT(std::hypot(e.radial_m, e.tangential_m), 0.1);
  }
}

}  // namespace
}  // namespace lidarcal::studies
