// SPDX-License-Identifier: BSD-3-Clause
// Do the predictive intervals of `calibrate --reference` hold what they claim, on sensors that
// follow a polynomial and on sensors that do not? For each seed: a simulated range sweep (one
// pole at 30 distances, simulation/range_sweep.hpp) split into interleaved halves; the range
// model fitted to one half (calibrateWithReference, with its model discrepancy), checked on the
// other, both ways round. Each held-out entry is checked
//   against its tape distance: the mean residual of its readings about f, inside the 68 % and
//     95 % predictive intervals (curve, discrepancy, the entry's noise and stated tape error);
//   against the truth: the fitted f minus the sensor's true mean reading at the entry's true
//     distance, inside the predictive intervals (curve and discrepancy), and inside the curve's
//     95 % interval alone (what the coefficients' covariance claims).
// docs/results/standard-errors.md, "Predictive intervals".
//
//   build/bench/predictive_coverage [--seeds 100] [--first-seed 2001]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "calibration/discrepancy.hpp"
#include "calibration/held_out.hpp"
#include "calibration/reference.hpp"
#include "common/rng.hpp"
#include "simulation/range_sweep.hpp"

namespace {

using namespace lidarcal;

/// One row of the table: a sensor, and how its tape distances were measured.
struct Case {
  std::string name;
  RangeModel model;
  double ripple_m = 0.0;  ///< ripple amplitude (wavelength 0.3 m, phase drawn per seed)
  double tape_m = 0.0;    ///< tape error drawn
  std::size_t scans = 10;
  double stated_m = -1.0;  ///< tape error stated in REF.json (negative: tape_m, as drawn)
};

struct Tally {
  int entries = 0, tape68 = 0, tape95 = 0, truth68 = 0, truth95 = 0, curve95 = 0, fits = 0,
      failed = 0;
  /// sums of squared errors over their predictive standard errors
  double tape_z2 = 0.0, truth_z2 = 0.0;
  std::vector<double> tau_m;
};

RangeModel paperSensor() {
  RangeModel m;
  m.bias.alpha = {0.0525, 0.8838, 0.0584};  // Alhashimi et al. 2016's sensor, as in data/scenes
  m.noise.kind = NoiseKind::squared;
  m.noise.sigma_e = 0.0019176;
  m.range_min_m = 0.05;
  m.range_max_m = 6.0;
  return m;
}

RangeModel timeOfFlightSensor() {
  RangeModel m;
  m.bias.alpha = {0.012, 0.985, 0.006};  // a few millimetres of bias, as the Hokuyo UST-30LX reads
  m.noise.kind = NoiseKind::constant;
  m.noise.sigma_e = 0.0042;
  m.range_min_m = 0.02;
  m.range_max_m = 30.0;
  return m;
}

/// 30 distances over 0.3-3.0 m, one drawn uniformly inside each of 30 equal cells (sorted).
std::vector<double> sweepDistances(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.1, 0.9);
  std::vector<double> d;
  for (int k = 0; k < 30; ++k) d.push_back(0.3 + (k + u(rng)) * 2.7 / 30.0);
  return d;
}

/// Fits on the readings of the stops with parity `fit`, checks the others against the sweep's
/// truth (`config`: the sensor's model, its effects and the pole's radius).
void checkHalf(const simulation::RangeSweep& sweep, const simulation::RangeSweepConfig& config,
               const calibration::ReferenceReadings& known, int fit, Tally& t) {
  const RangeModel& truth = config.model;
  const double radius_m = config.radius_m;
  const calibration::HalfCheck half = calibration::checkInterleavedHalf(known.readings, fit);
  const CalibrationModel& m = half.model;
  if (!m.status.ok()) {
    ++t.failed;
    return;
  }
  ++t.fits;
  t.tau_m.push_back(m.discrepancy.sigma_m);
  const double f68 = calibration::predictiveFactor(m.discrepancy, 0.6827);
  const double f95 = calibration::predictiveFactor(m.discrepancy, 0.95);
  for (const auto& h : half.held_out) {
    ++t.entries;
    t.tape68 += h.inside(m.discrepancy, 0.6827);
    t.tape95 += h.inside(m.discrepancy, 0.95);
    t.tape_z2 += h.residual_m * h.residual_m /
                 (h.predictive_se_m * h.predictive_se_m + h.entry_se_m * h.entry_se_m);
    // The sensor's true mean reading at the pole's nearest point, against the fit's.
    const double d = sweep.true_distance_m[known.matches[h.entry].stop] - radius_m;
    const double error = m.model.bias(d) - (truth.bias(d) + rangeRipple(config.effects, d));
    const double curve = calibration::curveStandardError(m, d);
    const double predictive = calibration::predictiveStandardError(curve, m.discrepancy);
    t.truth68 += std::abs(error) <= f68 * predictive;
    t.truth95 += std::abs(error) <= f95 * predictive;
    t.truth_z2 += error * error / (predictive * predictive);
    t.curve95 += std::abs(error) <= 1.96 * curve;
  }
}

void runCase(const Case& c, int first, int seeds) {
  Tally t;
  for (int seed = first; seed < first + seeds; ++seed) {
    std::mt19937_64 rng = makeRng(static_cast<std::uint64_t>(seed), 0x5ee9);
    simulation::RangeSweepConfig config;
    config.distances_m = sweepDistances(rng);
    config.model = c.model;
    config.scans_per_stop = c.scans;
    config.tape_error_m = c.tape_m;
    config.stated_sigma_m = c.stated_m < 0.0 ? c.tape_m : c.stated_m;
    config.effects.ripple_amplitude_m = c.ripple_m;
    config.effects.ripple_wavelength_m = 0.3;
    config.effects.ripple_phase_rad =
        std::uniform_real_distribution<double>(0.0, 6.283185307179586)(rng);
    const auto sweep = simulation::simulateRangeSweep(config, static_cast<std::uint64_t>(seed));
    const auto known = calibration::knownReadings(sweep.obs, sweep.reference, config.radius_m);
    for (int fit = 0; fit < 2; ++fit) checkHalf(sweep, config, known, fit, t);
    std::fprintf(stderr, "\r%s: seed %d of %d", c.name.c_str(), seed - first + 1, seeds);
  }
  std::fprintf(stderr, "\n");
  auto pct = [&](int k) { return 100.0 * k / std::max(t.entries, 1); };
  std::vector<double> tau = t.tau_m;
  std::sort(tau.begin(), tau.end());
  const double median_tau = tau.empty() ? std::nan("") : tau[tau.size() / 2];
  const double n = std::max(t.entries, 1);
  std::printf(
      "| %s | %d (%d refused) | %d | %.1f | %.1f %% | %.1f %% | %.2f | %.1f %% | %.1f %% | %.2f | "
      "%.1f %% |\n",
      c.name.c_str(), t.fits, t.failed, t.entries, 1000.0 * median_tau, pct(t.tape68),
      pct(t.tape95), std::sqrt(t.tape_z2 / n), pct(t.truth68), pct(t.truth95),
      std::sqrt(t.truth_z2 / n), pct(t.curve95));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Coverage of the predictive intervals of calibrate --reference on simulated range sweeps"};
  int seeds = 100, first = 2001;
  app.add_option("--seeds", seeds)->capture_default_str();
  app.add_option("--first-seed", first,
                 "Seeds first .. first + seeds - 1 (disjoint from those the tests use)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::vector<Case> cases = {
      {"triangulation sensor (polynomial bias), exact distances", paperSensor(), 0.0, 0.0, 10},
      {"triangulation sensor (polynomial bias), tape error 2 mm", paperSensor(), 0.0, 0.002, 10},
      {"triangulation sensor + ripple 4 mm, tape error 2 mm", paperSensor(), 0.004, 0.002, 10},
      {"time-of-flight sensor (polynomial bias), exact distances", timeOfFlightSensor(), 0.0, 0.0,
       20},
      {"time-of-flight sensor (polynomial bias), tape error 2 mm", timeOfFlightSensor(), 0.0, 0.002,
       20},
      {"time-of-flight sensor + ripple 4 mm, exact distances", timeOfFlightSensor(), 0.004, 0.0,
       20},
      {"time-of-flight sensor + ripple 4 mm, tape error 2 mm", timeOfFlightSensor(), 0.004, 0.002,
       20},
      // The Hokuyo sweep as docs/FINDINGS.md reads it: about 4 mm per recording in the reference
      // beyond the 2 mm its REF.json states, independent from one recording to the next.
      {"time-of-flight sensor (polynomial bias), tape error 4.5 mm, 2 mm stated",
       timeOfFlightSensor(), 0.0, 0.0045, 20, 0.002},
  };
  std::printf(
      "Predictive intervals on simulated range sweeps: 30 distances over 0.3-3.0 m, interleaved "
      "halves, fitted on "
      "each half and checked on the other; seeds %d-%d; ripple wavelength 0.3 m, random phase\n\n",
      first, first + seeds - 1);
  std::printf(
      "| sensor and tape | fits | held-out entries | median discrepancy [mm] | tape inside 68 %% | "
      "tape inside 95 %% "
      "| RMS z, tape | true bias inside 68 %% | true bias inside 95 %% | RMS z, true bias "
      "| true bias inside the curve's 95 %% |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Case& c : cases) runCase(c, first, seeds);
  return 0;
}
