// SPDX-License-Identifier: BSD-3-Clause
// lidarcal noise-consistency --observations OBS.csv --odometry ODO.csv --method kl-hill|ml --out
//   RESULT.json [--seed S] [--plot DIR] [--init SETTING.json] [--truth noise_truth.json] [--variant
//   sound|faithful] ...
// Estimates every sensor's range and bearing noise (mean, variance) and the process noise
// without ground truth: Sharma 2020's KL noise consistency with hill climbing, or maximum
// likelihood by variance-component estimation.

#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/noise_json.hpp"
#include "io/observations_csv.hpp"
#include "noise/problem.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/stages/noise_run.hpp"

namespace lidarcal::pipeline {
namespace {

struct NoiseOptions {
  std::string observations, odometry, out, method = "ml", variant = "sound", plot, init, truth;
  std::uint64_t seed = 1;
  int particles = 80;
  double step = 0.01;
  int jumps = 5;
  int max_evaluations = 5000;
  bool climb_process = false;
  bool fixed_means = false;
  bool no_biases = false;
  bool fixed_process = false;
  bool overwrite = false;
  bool record_time = false;
};

/// The estimator's options from the command line's.
NoiseRunOptions runOptions(const NoiseOptions& o) {
  NoiseRunOptions opts;
  opts.method = o.method == "kl-hill" ? NoiseMethod::kl_hill : NoiseMethod::ml;
  opts.faithful = o.variant == "faithful";
  opts.seed = o.seed;
  opts.kl.objective =
      opts.faithful ? noise::KlObjectiveConfig::faithful() : noise::KlObjectiveConfig::sound();
  opts.kl.objective.filter.particles = o.particles;
  opts.kl.climb.step = o.step;
  opts.kl.climb.max_jumps = o.jumps;
  opts.kl.climb.max_evaluations = o.max_evaluations;
  opts.kl.climb_process = o.climb_process;
  opts.kl.climb_means = !o.fixed_means;
  opts.ml.estimate_biases = !o.no_biases;
  opts.ml.estimate_process = !o.fixed_process;
  return opts;
}

/// The estimates on stderr, one line per sensor and one for the process.
void printNoiseSummary(const NoiseRun& run, const std::vector<int>& sensor_labels, bool kl) {
  std::fprintf(stderr, "%s: %s after %d %s in %.2f s\n", kl ? "kl-hill" : "ml", run.status.c_str(),
               run.evaluations, kl ? "evaluations" : "iterations", run.time_s);
  for (std::size_t s = 0; s < run.noise.sensors.size(); ++s) {
    const SensorNoise& n = run.noise.sensors[s];
    std::fprintf(
        stderr,
        "  sensor %d: range mean %+.4f m var %.5f m^2, bearing mean %+.4f rad var %.5f rad^2\n",
        s < sensor_labels.size() ? sensor_labels[s] : static_cast<int>(s), n.range_mean_m,
        n.range_var_m2, n.bearing_mean_rad, n.bearing_var_rad2);
  }
  const ProcessNoise& q = run.noise.process;
  std::fprintf(stderr, "  process var (%s): dx %.6f m^2, dy %.6f m^2, dtheta %.6f rad^2\n",
               run.process_estimated ? "estimated" : "assumed", q.dx_var_m2, q.dy_var_m2,
               q.dtheta_var_rad2);
}

void runNoiseConsistency(const NoiseOptions& o) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const std::string& input : {o.observations, o.odometry, o.init, o.truth})
    if (!input.empty() && fs::equivalent(input, o.out, ec))
      throw InputError(o.out, "--out", "is one of the inputs",
                       "inputs are never overwritten; choose another --out");
  if (o.fixed_process && o.init.empty())
    throw InputError("--fixed-process", "",
                     "keeps the process variances of --init, and no --init was given",
                     "pass --init SETTING.json with the known `process_var` (e.g. a result.json or "
                     "noise_truth.json)");
  if (!o.overwrite && fs::exists(o.out))
    throw InputError(o.out, "", "exists already", "choose another --out or pass --overwrite");
  // observations.csv's sensor ids, in the order of the indices 0..S-1
  std::vector<int> sensor_labels;
  const noise::NoiseProblem problem = noise::makeNoiseProblem(
      io::readObservations(o.observations, &sensor_labels), io::readOdometry(o.odometry));

  NoiseRunOptions opts = runOptions(o);
  if (!o.init.empty()) {
    opts.initial = io::readNoiseSetting(o.init, &sensor_labels);
    if (static_cast<int>(opts.initial->sensors.size()) != problem.sensors)
      throw InputError(
          o.init, "sensors",
          "lists " + std::to_string(opts.initial->sensors.size()) +
              " sensors but the observations have " + std::to_string(problem.sensors),
          "give one entry per sensor of observations.csv, in the ascending order of their ids");
  }
  std::optional<NoiseSetting> truth;
  if (!o.truth.empty()) truth = io::readNoiseSetting(o.truth, &sensor_labels);

  std::optional<io::StagedDirectory> plot_dir;
  if (!o.plot.empty()) plot_dir.emplace(o.plot, o.overwrite);

  const bool kl = opts.method == NoiseMethod::kl_hill;
  Progress progress(kl ? "kl-hill evaluations" : "ml iterations",
                    kl ? static_cast<std::size_t>(o.max_evaluations) : 0);
  const NoiseRun run = runNoiseEstimation(
      problem, opts, [&](std::size_t done, std::size_t total) { progress.update(done, total); });
  progress.finish();

  auto result = noiseRunToJson(run, problem, sensor_labels);
  // Off by default: the same input and seed give byte-identical files; the time is printed.
  if (o.record_time) result["time_s"] = run.time_s;
  io::writeTextAtomically(o.out, result.dump(2) + "\n");
  if (plot_dir) {
    const std::string problem_text = writeNoisePlots(plot_dir->path(), run, truth);
    plot_dir->commit();
    if (!problem_text.empty())
      std::fprintf(stderr, "lidarcal: warning: plots not drawn: %s\n", problem_text.c_str());
  }
  if (!quiet()) printNoiseSummary(run, sensor_labels, kl);
}

}  // namespace

void addNoiseConsistencyCommand(CLI::App& app) {
  auto o = std::make_shared<NoiseOptions>();
  CLI::App* sub = app.add_subcommand("noise-consistency",
                                     std::string("Estimate each sensor's range/bearing noise and "
                                                 "the process noise without ground truth (") +
                                         papers::kNoiseConsistency +
                                         ": KL hill climbing, or maximum likelihood)");
  sub->add_option("--observations", o->observations, "observations.csv (docs/FORMAT.md)")
      ->required();
  sub->add_option("--odometry", o->odometry, "odometry.csv (docs/FORMAT.md)")->required();
  sub->add_option("--method", o->method,
                  std::string("kl-hill: ") + papers::kNoiseConsistency +
                      " (particle filter + KL + hill climbing); ml: maximum likelihood by variance "
                      "components")
      ->check(CLI::IsMember({"kl-hill", "ml"}))
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "result.json (docs/FORMAT.md)")->required();
  sub->add_flag("--record-time", o->record_time,
                "Also write the wall time of the estimation (time_s) into the result: the file "
                "then differs between runs");
  sub->add_option("--seed", o->seed, "kl-hill: seed of the particle filter and the random jumps")
      ->capture_default_str();
  sub->add_option("--plot", o->plot,
                  "Directory for the trace plots (objective.png, params.png) and their data");
  sub->add_option(
      "--init", o->init,
      "Starting noise setting (JSON with `sensors` and `process_var`, e.g. a result.json); kl-hill "
      "default: means 0, variances 0.5, process 0. The process variances are the assumed ones "
      "unless "
      "estimated");
  sub->add_option("--truth", o->truth,
                  "noise_truth.json of a simulation: drawn as dashed lines in the plots");
  sub->add_option("--variant", o->variant,
                  "kl-hill objective: sound (ours) or faithful (as the method was published)")
      ->check(CLI::IsMember({"sound", "faithful"}))
      ->capture_default_str();
  sub->add_option("--particles", o->particles, "kl-hill: particles of the filter")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  sub->add_option("--step", o->step, "kl-hill: step of every parameter")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--jumps", o->jumps,
                  "kl-hill: random jumps in a row without improvement before stopping")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--max-evaluations", o->max_evaluations, "kl-hill: cap on objective evaluations")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_flag("--climb-process", o->climb_process,
                "kl-hill: also climb the process variances (the published method does not)");
  sub->add_flag("--fixed-means", o->fixed_means,
                "kl-hill: climb the variances only, means fixed at --init");
  sub->add_flag("--no-biases", o->no_biases, "ml: fix every bias at 0 instead of estimating it");
  sub->add_flag("--fixed-process", o->fixed_process,
                "ml: keep the process variances at --init instead of estimating them");
  sub->add_flag("--overwrite", o->overwrite, "Replace --out and --plot if they exist");
  sub->callback([o] { runNoiseConsistency(*o); });
}

}  // namespace lidarcal::pipeline
