// SPDX-License-Identifier: BSD-3-Clause
// Experiments behind docs/results/noise-consistency.md (run by bench/noise_experiments.sh).
//
//   noise_experiments side-by-side --scene S.json --init I.json --seed N --out DIR
//     [--kl-max-evaluations M] simulates the scene, runs Sharma 2020's KL hill climbing (the seed's
//     variant and ours, climbing means and variances, and variances only) and the ML estimator on
//     the same data, writes each result.json and its plots under DIR, and prints a Markdown table.
//   noise_experiments ml-study --scene S.json --seeds 20 [--process-given]
//     runs the ML estimator on seeds 1..20 and prints, per variance, the median estimate and the
//     median relative error against the truth; with --seeds 40 or more also the mean, the spread
//     against the estimator's own standard error, and how many disjoint 20-seed blocks have their
//     median within 10 %. --process-given fixes the process variances at the truth (Sharma 2020's
//     experiments assume the true process noise) and estimates the sensors' noise only.
//   noise_experiments objective-noise --scene S.json --init I.json [--seed N] [--evaluations 20]
//     spread of the KL objective at one setting over particle streams, per variant.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "io/noise_json.hpp"
#include "noise/problem.hpp"
#include "pipeline/stages/noise_run.hpp"
#include "simulation/observation_sim.hpp"

namespace fs = std::filesystem;
using namespace lidarcal;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The variances of a setting in a fixed order, with names.
std::vector<std::pair<std::string, double>> variances(const NoiseSetting& n) {
  std::vector<std::pair<std::string, double>> v;
  for (std::size_t s = 0; s < n.sensors.size(); ++s) {
    v.emplace_back("sensor " + std::to_string(s) + " range var", n.sensors[s].range_var_m2);
    v.emplace_back("sensor " + std::to_string(s) + " bearing var", n.sensors[s].bearing_var_rad2);
  }
  v.emplace_back("process dx var", n.process.dx_var_m2);
  v.emplace_back("process dy var", n.process.dy_var_m2);
  v.emplace_back("process dtheta var", n.process.dtheta_var_rad2);
  return v;
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, std::abs(v) < 1e-3 && v != 0.0 ? "%.1e" : "%.3f", v);
  return b;
}

std::string settingCell(const NoiseSetting& n, bool means) {
  std::string out;
  for (std::size_t s = 0; s < n.sensors.size(); ++s) {
    const SensorNoise& x = n.sensors[s];
    out += (s ? "; " : "") + std::string("[") + fmt(x.range_var_m2) + ", " +
           fmt(x.bearing_var_rad2) + "]";
    if (means) out += " μ[" + fmt(x.range_mean_m) + ", " + fmt(x.bearing_mean_rad) + "]";
  }
  return out;
}

std::string processCell(const NoiseSetting& n) {
  return "[" + fmt(n.process.dx_var_m2) + ", " + fmt(n.process.dy_var_m2) + ", " +
         fmt(n.process.dtheta_var_rad2) + "]";
}

/// One method of the side-by-side table: its label, the directory of its result and its options.
struct Row {
  std::string label, dir;
  pipeline::NoiseRunOptions options;
};

/// The side-by-side table's methods: the KL hill climbing (the seed's variant and ours, means and
/// variances or variances only; ours with the process variances when the truth has any) and ML.
std::vector<Row> sideBySideRows(const NoiseSetting& truth, const NoiseSetting& init,
                                std::uint64_t seed, int kl_max) {
  std::vector<Row> rows;
  for (const bool faithful : {true, false})
    for (const bool means : {true, false}) {
      Row r;
      r.label = std::string("KL hill, ") + (faithful ? "seed's variant" : "our variant") +
                (means ? ", means + vars" : ", vars only");
      r.dir = std::string("kl_") + (faithful ? "faithful" : "sound") + (means ? "" : "_vars");
      r.options.method = pipeline::NoiseMethod::kl_hill;
      r.options.faithful = faithful;
      r.options.seed = seed;
      r.options.initial = init;
      r.options.kl.objective =
          faithful ? noise::KlObjectiveConfig::faithful() : noise::KlObjectiveConfig::sound();
      r.options.kl.climb_means = means;
      r.options.kl.climb.max_evaluations = kl_max;
      rows.push_back(r);
    }
  if (truth.process.dx_var_m2 > 0 || truth.process.dy_var_m2 > 0 ||
      truth.process.dtheta_var_rad2 > 0) {
    Row r;
    r.label = "KL hill, our variant, vars + process vars";
    r.dir = "kl_sound_process";
    r.options.method = pipeline::NoiseMethod::kl_hill;
    r.options.seed = seed;
    r.options.initial = init;
    r.options.kl.objective = noise::KlObjectiveConfig::sound();
    r.options.kl.climb_means = false;
    r.options.kl.climb_process = true;
    r.options.kl.climb.max_evaluations = kl_max;
    rows.push_back(r);
  }
  Row ml;
  ml.label = "ML (VCE), ours";
  ml.dir = "ml";
  ml.options.method = pipeline::NoiseMethod::ml;
  rows.push_back(ml);
  // The ML estimator told what the hill climbing is told: the process noise as the start assumes
  // it.
  ml.label = "ML (VCE), ours, process as assumed";
  ml.dir = "ml_process_given";
  ml.options.ml.estimate_process = false;
  ml.options.ml.initial.process = init.process;
  rows.push_back(ml);
  return rows;
}

void sideBySide(const std::string& scene_file, const std::string& init_file, std::uint64_t seed,
                const std::string& out, int kl_max) {
  const ObservationScene scene = io::readObservationScene(scene_file);
  const NoiseSetting truth = trueNoise(scene);
  const NoiseSetting init = io::readNoiseSetting(init_file);
  const auto sim = simulation::simulateObservations(scene, seed);
  const noise::NoiseProblem problem = noise::makeNoiseProblem(sim.observations, sim.odometry);
  fs::create_directories(out);
  const std::vector<Row> rows = sideBySideRows(truth, init, seed, kl_max);

  std::printf(
      "Data: %d stops, %d sensors, %d landmarks, %zu observations (seed %llu). Truth: sensors %s, "
      "process %s; "
      "start of the hill climbing: %s, process %s.\n\n",
      problem.stops, problem.sensors, problem.landmarks, problem.observations.size(),
      static_cast<unsigned long long>(seed), settingCell(truth, true).c_str(),
      processCell(truth).c_str(), settingCell(init, false).c_str(), processCell(init).c_str());
  std::printf(
      "| method | sensors [range var m², bearing var rad²] μ[range mean m, bearing mean rad] | "
      "process var [dx, dy, dθ] | "
      "objective at end | evaluations | status | time (s) |\n|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    const pipeline::NoiseRun run = pipeline::runNoiseEstimation(problem, r.options);
    const fs::path dir = fs::path(out) / r.dir;
    fs::create_directories(dir);
    io::writeTextAtomically(dir / "result.json",
                            pipeline::noiseRunToJson(run, problem).dump(2) + "\n");
    const std::string plot_problem = pipeline::writeNoisePlots(dir, run, truth);
    if (!plot_problem.empty())
      std::fprintf(stderr, "warning: %s: %s\n", dir.c_str(), plot_problem.c_str());
    std::printf("| %s | %s | %s%s | %s | %d | %s | %.2f |\n", r.label.c_str(),
                settingCell(run.noise, true).c_str(), processCell(run.noise).c_str(),
                run.process_estimated ? "" : " (assumed)",
                fmt(run.objective_trace.empty() ? NAN : run.objective_trace.back()).c_str(),
                run.evaluations, run.status.c_str(), run.time_s);
    std::fflush(stdout);
  }
}

/// The ML estimator over seeds 1..seeds: per variance (in the order of variances()) the
/// estimates and the estimator's own standard errors, per sensor the bias errors.
struct MlStudy {
  int seeds = 0;
  std::vector<std::vector<double>> est, reported_se;
  std::vector<std::vector<double>> bias_err;  ///< per sensor: range, bearing
  std::vector<double> times, iterations;
  int not_converged = 0;
  std::size_t observations = 0;
  int stops = 0;
};

MlStudy runMlStudy(const ObservationScene& scene, const NoiseSetting& truth, int seeds,
                   bool process_given) {
  MlStudy r;
  r.seeds = seeds;
  r.est.resize(variances(truth).size());
  r.reported_se.resize(r.est.size());
  r.bias_err.resize(truth.sensors.size() * 2);
  for (int seed = 1; seed <= seeds; ++seed) {
    const auto sim = simulation::simulateObservations(scene, static_cast<std::uint64_t>(seed));
    const noise::NoiseProblem problem = noise::makeNoiseProblem(sim.observations, sim.odometry);
    r.observations = problem.observations.size();
    r.stops = problem.stops;
    pipeline::NoiseRunOptions o;
    o.method = pipeline::NoiseMethod::ml;
    if (process_given) {
      o.ml.estimate_process = false;
      // the sensors still start from the default, not the truth
      o.ml.initial.process = truth.process;
    }
    const pipeline::NoiseRun run = pipeline::runNoiseEstimation(problem, o);
    if (run.status != "ok") ++r.not_converged;
    const auto v = variances(run.noise);
    for (std::size_t i = 0; i < v.size(); ++i) {
      r.est[i].push_back(v[i].second);
      if (run.ml && i < run.ml->groups.size())
        r.reported_se[i].push_back(run.ml->groups[i].standard_error);
    }
    for (std::size_t s = 0; s < truth.sensors.size(); ++s) {
      r.bias_err[2 * s].push_back(
          std::abs(run.noise.sensors[s].range_mean_m - truth.sensors[s].range_mean_m));
      r.bias_err[2 * s + 1].push_back(
          std::abs(run.noise.sensors[s].bearing_mean_rad - truth.sensors[s].bearing_mean_rad));
    }
    r.times.push_back(run.time_s);
    r.iterations.push_back(run.evaluations);
  }
  return r;
}

/// Per variance: the median estimate and the median relative error against the truth.
void printMedians(const MlStudy& r, const std::vector<std::pair<std::string, double>>& names,
                  std::size_t shown) {
  std::printf(
      "| variance | truth | median estimate | median estimate / truth − 1 | median \\|rel. "
      "error\\| | within 10%% (seeds) |\n|---|---|---|---|---|---|\n");
  for (std::size_t i = 0; i < shown; ++i) {
    const double t = names[i].second;
    const double med = median(r.est[i]);
    if (t > 0) {
      std::vector<double> rel;
      int within = 0;
      for (double e : r.est[i]) {
        rel.push_back(std::abs(e / t - 1.0));
        within += std::abs(e / t - 1.0) <= 0.10;
      }
      std::printf("| %s | %s | %s | %+.1f %% | %.1f %% | %d / %d |\n", names[i].first.c_str(),
                  fmt(t).c_str(), fmt(med).c_str(), 100.0 * (med / t - 1.0), 100.0 * median(rel),
                  within, r.seeds);
    } else {
      std::printf("| %s | 0 | %s | (truth 0) | max %s | |\n", names[i].first.c_str(),
                  fmt(med).c_str(),
                  fmt(*std::max_element(r.est[i].begin(), r.est[i].end())).c_str());
    }
  }
}

/// Over 40 seeds or more: the mean, the spread against the estimator's own standard error, and
/// the sampling spread of a 20-seed median (the seeds cut into consecutive blocks of 20).
void printBlocks(const MlStudy& r, const std::vector<std::pair<std::string, double>>& names,
                 std::size_t shown) {
  const int seeds = r.seeds;
  const int blocks = seeds / 20;
  std::printf(
      "\nOver %d seeds: mean estimate, the spread of the estimates (standard deviation / truth) "
      "against the "
      "estimator's own standard error (median over seeds, / truth), and the %d disjoint blocks "
      "of 20 seeds "
      "(1-20, 21-40, ...) whose median estimate is within 10 %% of the truth.\n\n",
      seeds, blocks);
  std::printf(
      "| variance | mean estimate / truth − 1 | std of the estimates / truth | reported standard "
      "error / truth | "
      "20-seed medians within 10 %% | range of the 20-seed medians / truth − 1 "
      "|\n|---|---|---|---|---|---|\n");
  for (std::size_t i = 0; i < shown; ++i) {
    const double t = names[i].second;
    if (!(t > 0)) continue;
    const std::vector<double>& est = r.est[i];
    double mean = 0.0, var = 0.0;
    for (double e : est) mean += e / static_cast<double>(seeds);
    for (double e : est) var += (e - mean) * (e - mean) / static_cast<double>(seeds - 1);
    int within = 0;
    double lo = 1e300, hi = -1e300;
    for (int b = 0; b < blocks; ++b) {
      const double m =
          median(std::vector<double>(est.begin() + 20 * b, est.begin() + 20 * (b + 1))) / t - 1.0;
      within += std::abs(m) <= 0.10;
      lo = std::min(lo, m), hi = std::max(hi, m);
    }
    char se[32] = "";
    if (!r.reported_se[i].empty())
      std::snprintf(se, sizeof se, "%.3f", median(r.reported_se[i]) / t);
    std::printf("| %s | %+.1f %% | %.3f | %s | %d / %d | %+.1f %% .. %+.1f %% |\n",
                names[i].first.c_str(), 100.0 * (mean / t - 1.0), std::sqrt(var) / t, se, within,
                blocks, 100.0 * lo, 100.0 * hi);
  }
}

void mlStudy(const std::string& scene_file, int seeds, bool process_given) {
  const ObservationScene scene = io::readObservationScene(scene_file);
  const NoiseSetting truth = trueNoise(scene);
  const auto names = variances(truth);
  // Rows of the tables: every variance, or the sensors' only when the process variances are given.
  const std::size_t shown = process_given ? 2 * truth.sensors.size() : names.size();
  const MlStudy r = runMlStudy(scene, truth, seeds, process_given);
  std::printf(
      "%d seeds; each %d stops, %zu observations. Median wall time %.2f s, median %g iterations, "
      "%d not converged.\n\n",
      seeds, r.stops, r.observations, median(r.times), median(r.iterations), r.not_converged);
  if (process_given)
    std::printf(
        "Process variances given (fixed at the truth %s, as Sharma 2020 assumes them); the "
        "sensors' variances and "
        "biases estimated.\n\n",
        processCell(truth).c_str());
  printMedians(r, names, shown);
  if (seeds >= 40) printBlocks(r, names, shown);
  std::printf("\nMedian absolute bias error per sensor (range m, bearing rad):");
  for (std::size_t s = 0; s < truth.sensors.size(); ++s)
    std::printf(" sensor %zu [%s, %s]", s, fmt(median(r.bias_err[2 * s])).c_str(),
                fmt(median(r.bias_err[2 * s + 1])).c_str());
  std::printf("\n");
}

// Spread of the objective at one setting over `n` evaluations (fresh particle streams for the
// seed's variant, common random numbers for ours) against the change to a neighbour.
void objectiveNoise(const std::string& scene_file, const std::string& init_file, std::uint64_t seed,
                    int n) {
  const ObservationScene scene = io::readObservationScene(scene_file);
  const auto sim = simulation::simulateObservations(scene, seed);
  const noise::NoiseProblem problem = noise::makeNoiseProblem(sim.observations, sim.odometry);
  const NoiseSetting init = io::readNoiseSetting(init_file);
  NoiseSetting neighbour = init;
  neighbour.sensors[0].range_var_m2 += 0.01;
  std::printf(
      "| variant | objective at the start: mean | std over %d evaluations | neighbour (sensor 0 "
      "range var + 0.01) − start |\n|---|---|---|---|\n",
      n);
  for (const bool faithful : {true, false}) {
    const auto config =
        faithful ? noise::KlObjectiveConfig::faithful() : noise::KlObjectiveConfig::sound();
    std::vector<double> v, d;
    for (int e = 0; e < n; ++e) {
      const double a =
          noise::evaluateKlObjective(problem, init, config, seed, 2 * static_cast<std::uint64_t>(e))
              .total;
      const double b = noise::evaluateKlObjective(problem, neighbour, config, seed,
                                                  2 * static_cast<std::uint64_t>(e) + 1)
                           .total;
      v.push_back(a);
      d.push_back(b - a);
    }
    double mean = 0, var = 0;
    for (double x : v) mean += x / n;
    for (double x : v) var += (x - mean) * (x - mean) / std::max(1, n - 1);
    std::printf("| %s | %.4f | %.4f | median %+.4f (range %+.4f .. %+.4f) |\n",
                faithful ? "seed's" : "ours", mean, std::sqrt(var), median(d),
                *std::min_element(d.begin(), d.end()), *std::max_element(d.begin(), d.end()));
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Noise-consistency experiments for docs/RESULTS.md"};
  app.require_subcommand(1);
  std::string scene, init, out;
  std::uint64_t seed = 1;
  int seeds = 20, kl_max = 5000;
  CLI::App* sbs = app.add_subcommand("side-by-side", "Both methods on one simulated data set");
  sbs->add_option("--scene", scene)->required();
  sbs->add_option("--init", init)->required();
  sbs->add_option("--seed", seed);
  sbs->add_option("--out", out)->required();
  sbs->add_option("--kl-max-evaluations", kl_max);
  CLI::App* study = app.add_subcommand("ml-study", "ML over many seeds");
  study->add_option("--scene", scene)->required();
  study->add_option("--seeds", seeds);
  bool process_given = false;
  study->add_flag("--process-given", process_given,
                  "Fix the process variances at the truth; estimate the sensors' noise only");
  int evaluations = 20;
  CLI::App* noise =
      app.add_subcommand("objective-noise", "Spread of the KL objective over particle streams");
  noise->add_option("--scene", scene)->required();
  noise->add_option("--init", init)->required();
  noise->add_option("--seed", seed);
  noise->add_option("--evaluations", evaluations);
  CLI11_PARSE(app, argc, argv);
  try {
    if (sbs->parsed()) sideBySide(scene, init, seed, out, kl_max);
    if (study->parsed()) mlStudy(scene, seeds, process_given);
    if (noise->parsed()) objectiveNoise(scene, init, seed, evaluations);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "noise_experiments: %s\n", e.what());
    return 1;
  }
  return 0;
}
