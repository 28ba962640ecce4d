// SPDX-License-Identifier: BSD-3-Clause
// Do the standard errors mean what they say? For each seed: simulate a calibration sequence,
// calibrate it through the command line (the joint refinement without ground truth, and against
// tape distances taken from the simulator's truth: `calibrate --reference`, alone and for a few
// stops inside the self-calibration: `--reference-fit combined`), and check whether
// the 95 % interval f(d) +- 1.96 SE(f(d)) holds the simulated sensor's true f(d) at a few
// distances inside the fitted range, and each coefficient's interval its true value; and the
// predictive 95 % interval (curve and model discrepancy, Student t: calibration/discrepancy.hpp)
// at the same distances, and the RMS error of f(d) there; for `calibrate --reference` also that of
// the noise law's fit of the same order from model.json's order table, the baseline of the
// random-effects refit (docs/results/standard-errors.md).
//
// A scene whose sensor has a ripple (sensor.effects.ripple_amplitude_m) gets the ripple's phase
// drawn per seed, and the truth is the polynomial plus the ripple.
//
//   build/bench/coverage --scene data/scenes/paper_field.json --seeds 100 [--first-seed 1001]
//       [--scans-per-stop 10] [--work /tmp/coverage] [--joint-args "--max-order 2"] [--taped-stops
//       5]

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "calibration/discrepancy.hpp"
#include "calibration/held_out.hpp"
#include "common/range_effects.hpp"
#include "io/model_io.hpp"
#include "io/reference_io.hpp"
#include "io/scene_io.hpp"
#include "simulation/tape_reference.hpp"

namespace fs = std::filesystem;

namespace {

bool sh(const std::string& cmd) { return std::system((cmd + " >/dev/null 2>&1").c_str()) == 0; }

nlohmann::json readJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

/// REF.json a user with a tape would write: each visible pole's distance from the true pose of
/// every stop, with its bearing (poles within 4 m, none in front of another); each distance
/// with a tape error drawn from N(0, tape_sigma_m^2) (0: exact).
/// Only the first `stops` stops' distances when stops >= 0.
void tapeReference(const fs::path& truth, const fs::path& out, double tape_sigma_m,
                   std::uint64_t seed, int stops = -1) {
  lidarcal::TapeConfig config;
  config.sigma_m = tape_sigma_m;
  config.seed = seed;
  lidarcal::Reference ref = lidarcal::tapeReference(lidarcal::io::readTruth(truth), config);
  auto& d = ref.distances;
  if (stops >= 0)
    d.erase(
        std::remove_if(d.begin(), d.end(),
                       [&](const auto& e) { return e.stop >= static_cast<std::size_t>(stops); }),
        d.end());
  lidarcal::io::writeReference(out, ref);
}

double poly(const std::vector<double>& a, double d) {
  double f = 0.0;
  for (std::size_t i = a.size(); i-- > 0;) f = f * d + a[i];
  return f;
}

struct Tally {
  std::vector<int> covered_f, n_f;
  int covered_alpha = 0, n_alpha = 0, fits = 0, failed = 0, covered_predictive = 0;
  double sum_z2 = 0.0, sum_error2 = 0.0, sum_law_error2 = 0.0;
  int n_z = 0, n_law = 0;
};

/// The coefficients of the order table's fit of `order` in model.json, empty when it has none.
/// For `calibrate --reference` that is the noise law's fit the order was chosen from, before the
/// random-effects refit the model adopts.
std::vector<double> tableFit(const nlohmann::json& model, int order) {
  for (const auto& row : model["order_selection"]["table"])
    if (row["order"].get<int>() == order) return row["alpha"].get<std::vector<double>>();
  return {};
}

/// Checks the model.json `file` against the true bias; with `noise_law`, also the order table's
/// fit of the chosen order (the baseline of the random-effects refit).
void check(const fs::path& file, const std::vector<double>& truth, const lidarcal::RangeEffects& fx,
           const std::vector<double>& at, Tally& t, bool noise_law = false) {
  const lidarcal::CalibrationModel m = lidarcal::io::readModel(file);
  const std::vector<double> law =
      noise_law ? tableFit(readJson(file), m.model.bias.order()) : std::vector<double>{};
  const std::vector<double>& a = m.model.bias.alpha;
  const std::vector<double>& c = m.alpha_covariance;
  const std::size_t n = a.size();
  if (c.size() != n * n || !m.fitted_range_m) {
    ++t.failed;
    return;
  }
  ++t.fits;
  const double t95 = lidarcal::calibration::predictiveFactor(m.discrepancy, 0.95);
  const auto [lo, hi] = *m.fitted_range_m;
  for (std::size_t k = 0; k < at.size(); ++k) {
    if (at[k] < lo || at[k] > hi) continue;
    const double se = lidarcal::calibration::curveStandardError(m, at[k]);
    // The sensor's true mean reading: the scene's polynomial and its ripple, if any.
    const double truth_k = poly(truth, at[k]) + lidarcal::rangeRipple(fx, at[k]);
    const double error = m.model.bias(at[k]) - truth_k;
    const double z = error / se;
    t.sum_error2 += error * error;
    if (!law.empty()) t.sum_law_error2 += std::pow(poly(law, at[k]) - truth_k, 2), ++t.n_law;
    t.covered_f[k] += std::abs(z) <= 1.96;
    t.covered_predictive +=
        std::abs(error) <= t95 * lidarcal::calibration::predictiveStandardError(se, m.discrepancy);
    ++t.n_f[k];
    t.sum_z2 += z * z;
    ++t.n_z;
  }
  // Coefficients only when the chosen order is the true one (else they estimate something else).
  if (n == truth.size())
    for (std::size_t i = 0; i < n; ++i) {
      t.covered_alpha += std::abs(a[i] - truth[i]) <= 1.96 * std::sqrt(c[i * n + i]);
      ++t.n_alpha;
    }
}

void print(const char* name, const Tally& t, const std::vector<double>& at) {
  std::printf("| %s | %d (%d without) |", name, t.fits, t.failed);
  for (std::size_t k = 0; k < at.size(); ++k)
    if (t.n_f[k])
      std::printf(" %d/%d = %.0f %% |", t.covered_f[k], t.n_f[k],
                  100.0 * t.covered_f[k] / t.n_f[k]);
    else
      std::printf(" - |");
  if (t.n_alpha)
    std::printf(" %d/%d = %.0f %% |", t.covered_alpha, t.n_alpha,
                100.0 * t.covered_alpha / t.n_alpha);
  else
    std::printf(" - |");
  std::printf(" %.2f |", t.n_z ? std::sqrt(t.sum_z2 / t.n_z) : std::nan(""));
  if (t.n_z)
    std::printf(" %d/%d = %.0f %% |", t.covered_predictive, t.n_z,
                100.0 * t.covered_predictive / t.n_z);
  else
    std::printf(" - |");
  std::printf(" %.2f |", t.n_z ? 1000.0 * std::sqrt(t.sum_error2 / t.n_z) : std::nan(""));
  if (t.n_law)
    std::printf(" %.2f |\n", 1000.0 * std::sqrt(t.sum_law_error2 / t.n_law));
  else
    std::printf(" - |\n");
}

/// The command line: the scene, the seeds, and how each is simulated and calibrated.
struct Options {
  std::string scene = "data/scenes/paper_field.json", work = "/tmp/lidarcal-coverage";
  int seeds = 100, first = 1001, scans = 10;
  double tape_sigma = 0.002;  ///< standard deviation of the simulated tape error, metres
  std::string joint_args;     ///< more options for the joint refinement's calibrate
  int taped_stops = 5;        ///< stops whose tape distances join the self-calibration
};

/// One tally per row of the table.
struct Tallies {
  Tally joint, closed, reference, taped, combined;
};

/// The scene file of `seed`, `drawn` its scene: a rippled sensor gets its ripple's phase drawn
/// per seed (a predictive interval speaks of a distance the fit did not see, not of one fixed
/// point of one fixed ripple), written to the work directory; any other scene is the given one.
std::string sceneOfSeed(const Options& o, const lidarcal::Scene& base, int seed,
                        lidarcal::Scene& drawn) {
  drawn = base;
  std::string scene_file = o.scene;
  if (drawn.sensor.effects.ripple_amplitude_m != 0.0) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) ^ 0x9e3779b97f4a7c15ULL);
    drawn.sensor.effects.ripple_phase_rad =
        std::uniform_real_distribution<double>(0.0, 6.283185307179586)(rng);
    scene_file = (fs::path(o.work) / ("scene-" + std::to_string(seed) + ".json")).string();
    std::ofstream(scene_file) << lidarcal::io::sceneToJson(drawn).dump(1);
  }
  return scene_file;
}

/// Simulates `seed`, calibrates it each way the table compares and tallies the checks; false
/// when the simulation fails.
bool runSeed(const Options& o, const lidarcal::Scene& base, int seed, const std::vector<double>& at,
             Tallies& t) {
  const std::string exe = LIDARCAL_EXE;
  const fs::path dir = fs::path(o.work) / ("s" + std::to_string(seed));
  lidarcal::Scene drawn;
  const std::string scene_file = sceneOfSeed(o, base, seed, drawn);
  const lidarcal::RangeEffects& fx = drawn.sensor.effects;
  if (!sh(exe + " simulate -q --scene " + scene_file + " --out " + dir.string() + " --seed " +
          std::to_string(seed) + " --scans-per-stop " + std::to_string(o.scans) + " --overwrite")) {
    std::fprintf(stderr, "simulate failed for seed %d\n", seed);
    return false;
  }
  const auto truth_json = readJson(dir / "truth.json");
  const std::vector<double> truth = truth_json["model"]["bias_alpha"];
  if (sh(exe + " calibrate -q " + o.joint_args + " " + (dir / "scans").string() + " -o " +
         (dir / "joint.json").string() + " --overwrite"))
    check(dir / "joint.json", truth, fx, at, t.joint);
  else
    ++t.joint.failed;
  if (sh(exe + " calibrate -q --method closed-form " + (dir / "scans").string() + " -o " +
         (dir / "cf.json").string() + " --overwrite"))
    check(dir / "cf.json", truth, fx, at, t.closed);
  else
    ++t.closed.failed;
  tapeReference(dir / "truth.json", dir / "ref.json", 0.0, 0);
  if (sh(exe + " calibrate -q " + (dir / "scans").string() + " --reference " +
         (dir / "ref.json").string() + " -o " + (dir / "ref-model.json").string() + " --overwrite"))
    check(dir / "ref-model.json", truth, fx, at, t.reference, true);
  else
    ++t.reference.failed;
  tapeReference(dir / "truth.json", dir / "tape.json", o.tape_sigma,
                static_cast<std::uint64_t>(seed));
  if (sh(exe + " calibrate -q " + (dir / "scans").string() + " --reference " +
         (dir / "tape.json").string() + " -o " + (dir / "tape-model.json").string() +
         " --overwrite"))
    check(dir / "tape-model.json", truth, fx, at, t.taped, true);
  else
    ++t.taped.failed;
  tapeReference(dir / "truth.json", dir / "taped-stops.json", o.tape_sigma,
                static_cast<std::uint64_t>(seed), o.taped_stops);
  if (sh(exe + " calibrate -q " + (dir / "scans").string() + " --reference " +
         (dir / "taped-stops.json").string() + " --reference-fit combined -o " +
         (dir / "combined.json").string() + " --overwrite"))
    check(dir / "combined.json", truth, fx, at, t.combined);
  else
    ++t.combined.failed;
  fs::remove_all(dir / "scans");
  return true;
}

void printTable(const Options& o, const std::vector<double>& at, const Tallies& t) {
  std::printf("Coverage of the 95 %% intervals, %s, seeds %d-%d, %d scans per stop\n\n",
              o.scene.c_str(), o.first, o.first + o.seeds - 1, o.scans);
  std::printf("| method | fits (without SE) |");
  for (double d : at) std::printf(" f(%.0f m) |", d);
  std::printf(
      " alpha_i (true order chosen) | RMS of z = error / SE | predictive 95 %%, f(d) at all three |"
      " RMS error of f(d) at all three [mm] | the same, noise-law fit of that order [mm] "
      "|\n|---|---|");
  for (std::size_t k = 0; k < at.size(); ++k) std::printf("---|");
  std::printf("---|---|---|---|---|\n");
  print("joint refinement (no ground truth)", t.joint, at);
  print("closed form of Alhashimi et al. 2021, jackknife SE (no ground truth)", t.closed, at);
  print("against exact distances (--reference)", t.reference, at);
  char name[96];
  std::snprintf(name, sizeof name, "against tape distances, tape error %.1f mm (--reference)",
                1000.0 * o.tape_sigma);
  print(name, t.taped, at);
  std::snprintf(
      name, sizeof name,
      "joint refinement with the first %d stops' tape distances (--reference-fit combined)",
      o.taped_stops);
  print(name, t.combined, at);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Coverage of the 95 % intervals of the calibrated range model over simulated seeds"};
  Options o;
  app.add_option("--scene", o.scene)->capture_default_str();
  app.add_option("--seeds", o.seeds)->capture_default_str();
  app.add_option("--first-seed", o.first,
                 "Seeds first .. first + seeds - 1 (disjoint from those the tests use)")
      ->capture_default_str();
  app.add_option("--scans-per-stop", o.scans)->capture_default_str();
  app.add_option("--work", o.work)->capture_default_str();
  app.add_option("--tape-sigma", o.tape_sigma,
                 "Standard deviation of the simulated tape error, metres")
      ->capture_default_str();
  app.add_option("--joint-args", o.joint_args,
                 "More options for the joint refinement's calibrate (e.g. \"--max-order 2\")");
  app.add_option("--taped-stops", o.taped_stops,
                 "Stops whose tape distances join the self-calibration (--reference-fit combined) "
                 "in the last row")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  const std::vector<double> at = {1.0, 2.0, 3.0};
  const lidarcal::Scene base = lidarcal::io::readScene(o.scene);
  Tally empty{std::vector<int>(at.size()), std::vector<int>(at.size())};
  Tallies t{empty, empty, empty, empty, empty};
  fs::create_directories(o.work);
  for (int seed = o.first; seed < o.first + o.seeds; ++seed) {
    if (!runSeed(o, base, seed, at, t)) return 1;
    std::fprintf(stderr, "\rseed %d of %d", seed - o.first + 1, o.seeds);
  }
  std::fprintf(stderr, "\n");
  printTable(o, at, t);
  return 0;
}
