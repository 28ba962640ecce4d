// SPDX-License-Identifier: BSD-3-Clause
// lidarcal montecarlo --study fig7|fig8|fig9|fig10|fig11|all --trials N --out DIR: the Monte Carlo
// study of Alhashimi et al. 2021 (sections 4.1-4.2, Figs. 7-11) with the paper's closed form, our
// joint refinement and the oracle side by side. Writes DIR/<fig>.csv, <fig>.gp, <fig>.png, <fig>.md
// and DIR/summary.md. Interrupting (Ctrl-C) stops after the trials in progress and writes nothing;
// a plot gnuplot cannot draw fails the command (nothing written); without gnuplot the plots are
// skipped and the command says so. With --shard K/N it runs one of N disjoint slices of the trials
// and writes them for `lidarcal montecarlo-merge` (pipeline/stages/montecarlo_shard.hpp).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include <glog/logging.h>
#include <CLI/CLI.hpp>

#include "io/atomic_file.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/words.hpp"
#include "pipeline/stages/montecarlo_setup.hpp"
#include "pipeline/stages/montecarlo_shard.hpp"
#include "studies/study.hpp"

namespace lidarcal::pipeline {
namespace {

/// Set by SIGINT while the trials run; the workers stop after their current trial.
std::atomic<bool> g_interrupted{false};
extern "C" void onInterrupt(int) { g_interrupted = true; }

/// Installs the SIGINT handler for its lifetime.
class InterruptGuard {
 public:
  InterruptGuard() { previous_ = std::signal(SIGINT, onInterrupt); }
  ~InterruptGuard() { std::signal(SIGINT, previous_); }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

 private:
  void (*previous_)(int) = SIG_DFL;
};

/// Quiets Ceres for the study: it logs through glog when a solve struggles (WARNING: a step
/// failed and is retried with more damping; ERROR: the solve gave up, and the estimator either
/// reports a failure, counted in the CSV's *_failed columns, or goes on from its last usable
/// solution). Over thousands of trials these lines would bury the progress bar.
void quietSolver() {
  FLAGS_minloglevel = std::max(FLAGS_minloglevel, static_cast<int>(google::GLOG_FATAL));
}

/// Runs slice run.shard_index of the study and writes it for the merge. False when interrupted.
bool runShard(const MonteCarloOptions& o, const StudySetup& setup, studies::RunOptions run) {
  const auto cells = studies::studyCells(setup.figures, setup.grids);
  const auto slice = studies::shardTrials(cells.size(), run);
  io::StagedDirectory out(o.out, o.overwrite);
  if (!quiet())
    std::fprintf(stderr, "montecarlo: shard %zu/%zu, %zu of the %zu cells x %zu trials, %s\n",
                 run.shard_index + 1, run.shard_count, slice.size(), cells.size(), run.trials,
                 plural(static_cast<std::size_t>(run.threads), "thread").c_str());
  const auto start = std::chrono::steady_clock::now();
  studies::StudyRun result;
  {
    Progress progress("montecarlo", slice.size());
    run.on_progress = [&](std::size_t done, std::size_t) { progress.update(done); };
    result = studies::runCells(setup.config, cells, run);
    if (!result.interrupted) progress.finish();
  }
  if (result.interrupted || g_interrupted) return false;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  writeShard(out.path(), studyIdentity(o, setup), run, slice, result);
  out.commit();
  std::printf("Monte Carlo shard %zu/%zu: %zu trials in %.1f s (%s)\n", run.shard_index + 1,
              run.shard_count, slice.size(), seconds,
              plural(static_cast<std::size_t>(run.threads), "thread").c_str());
  std::printf(
      "Output: %s (shard.json, trials.csv; merge every shard with lidarcal montecarlo-merge)\n",
      o.out.c_str());
  return true;
}

/// Runs the whole study. False when interrupted (nothing written).
bool runWholeStudy(const MonteCarloOptions& o, const StudySetup& setup, studies::RunOptions run) {
  io::StagedDirectory out(o.out, o.overwrite);
  const auto cells = studies::studyCells(setup.figures, setup.grids);
  if (!quiet())
    std::fprintf(stderr,
                 "montecarlo: %zu cells x %zu trials (joint refinement on %zu), %s level, %s\n",
                 cells.size(), run.trials, run.joint_trials, studies::toString(setup.config.level),
                 plural(static_cast<std::size_t>(run.threads), "thread").c_str());
  const auto start = std::chrono::steady_clock::now();
  studies::StudyOutput result;
  {
    Progress progress("montecarlo", cells.size() * run.trials);
    run.on_progress = [&](std::size_t done, std::size_t) { progress.update(done); };
    result = studies::runStudy(setup.figures, setup.grids, setup.config, run);
    if (!result.interrupted) progress.finish();
  }
  if (result.interrupted) return false;  // `out` is discarded: nothing is written
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string plots = writeStudyOutput(out.path(), result);
  if (g_interrupted) return false;
  out.commit();
  const double trials = static_cast<double>(cells.size() * run.trials);
  std::printf("Monte Carlo study: %zu cells x %zu trials in %.1f s (%.1f trials/s, %s)\n",
              cells.size(), run.trials, seconds, trials / seconds,
              plural(static_cast<std::size_t>(run.threads), "thread").c_str());
  std::printf("Output: %s (summary.md; per figure .csv, .png, .gp, .md)\n", o.out.c_str());
  if (!plots.empty()) std::printf("Plots: %s\n", plots.c_str());
  return true;
}

/// Returns false when interrupted (nothing written).
bool runMonteCarlo(const MonteCarloOptions& o) {
  const StudySetup setup = studySetup(o);
  studies::RunOptions run = setup.run;
  if (!o.shard.empty()) parseShard(o.shard, run);
  run.stop = &g_interrupted;
  // From here to the commit a SIGINT only sets the flag: the trials stop, nothing is committed.
  g_interrupted = false;
  InterruptGuard guard;
  quietSolver();
  return o.shard.empty() ? runWholeStudy(o, setup, run) : runShard(o, setup, run);
}

/// What each trial simulates: the level, the noise, the scene and the orders tried.
void addSimulationOptions(CLI::App& sub, MonteCarloOptions& o) {
  sub.add_option("--level", o.level,
                 "landmark: Alhashimi et al. 2021 eqs. 3, 5, 8 with beams ray-cast on each "
                 "landmark (fast); scan: whole scans "
                 "ray-cast and the detector in the loop")
      ->capture_default_str();
  sub.add_option("--angle-noise", o.angle_noise,
                 "What sigma_theta perturbs: heading (the robot's heading at each stop: every "
                 "beam of the stop "
                 "turns; default, the scan level's only model), beams (eq. 5: each landmark's "
                 "centre bearing and "
                 "beam angles at each stop) or bearing (eq. 5 on the centre bearing only: the "
                 "joint refinement, "
                 "which fits beam angles, does not see it)")
      ->capture_default_str();
  sub.add_option("--noise-law", o.noise_law,
                 "Simulated range noise: paper (Alhashimi et al. 2021: 5 % of f(d)) or squared "
                 "(Alhashimi et al. 2016: sigma_e f(d)^2, the "
                 "same at 3 m)")
      ->capture_default_str();
  sub.add_option("--max-distance", o.max_distance_m,
                 "Farthest landmark surface from any stop, metres (Alhashimi et al. 2021, section "
                 "4.3, keeps them within 5 m)")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 100.0));
  sub.add_option("--range-max", o.range_max_m, "Upper end of the sensor's reading window, metres")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  sub.add_option("--scans-per-stop", o.scans_per_stop, "Scans averaged at each stop")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub.add_option("--stops", o.stops, "Stops along the path")
      ->capture_default_str()
      ->check(CLI::Range(3, 1000));
  sub.add_option("--step", o.step_m, "Distance between stops, metres")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub.add_option("--max-order", o.max_order, "Highest polynomial order tried (n_max)")
      ->capture_default_str()
      ->check(CLI::Range(1, 6));
  sub.add_option("--noise-scale", o.noise_scale,
                 "Multiplies the paper's range noise (beta = 0.05 alpha); default 1 at the "
                 "landmark level, 0.2 at "
                 "the scan level (the detector cannot find the poles through the paper's noise)")
      ->check(CLI::NonNegativeNumber);
}

}  // namespace

void addMonteCarloCommand(CLI::App& app) {
  auto o = std::make_shared<MonteCarloOptions>();
  CLI::App* sub = app.add_subcommand("montecarlo",
                                     "Monte Carlo study of Alhashimi et al. 2021 (Figs. 7-11): the "
                                     "paper's closed form, the joint refinement and the oracle "
                                     "over noise levels and landmark counts. Ctrl-C stops cleanly "
                                     "and writes nothing (OUT appears only when "
                                     "complete).");
  sub->add_option("--study", o->study, "fig7, fig8, fig9, fig10, fig11 or all")
      ->capture_default_str();
  sub->add_option("-o,--out", o->out,
                  "Output directory (created whole at the end; see docs/FORMAT.md)")
      ->required();
  sub->add_option("--trials", o->trials,
                  "Trials per cell (default 1000 at the landmark level, 100 at the scan level; "
                  "--quick: 100 / 10)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--joint-trials", o->joint_trials,
                  "Run the joint refinement on the first N trials of each cell (default 200 "
                  "landmark level, 50 scan "
                  "level; --quick: 10 / 5)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--no-joint", o->no_joint, "Skip the joint refinement");
  sub->add_option("--threads", o->threads,
                  "Worker threads (default: all cores); the output does not depend on it")
      ->check(CLI::PositiveNumber);
  sub->add_option("--seed", o->seed, "Study seed; the same seed and options give the same bytes")
      ->capture_default_str();
  addSimulationOptions(*sub, *o);
  sub->add_flag("--quick", o->quick, "Coarse grids and fewer trials, for a first look");
  sub->add_option("--shard", o->shard,
                  "K/N: run only the K-th of N disjoint slices of the trials (each trial seeded as "
                  "in the whole study) "
                  "and write them to OUT for `lidarcal montecarlo-merge`, which makes the whole "
                  "study's files byte for "
                  "byte; one slice per batch task (Slurm: $((SLURM_ARRAY_TASK_ID + 1))/N)");
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  sub->callback([o] {
    if (!runMonteCarlo(*o)) {
      std::fprintf(stderr, "\nlidarcal: montecarlo interrupted; nothing was written\n");
      std::exit(130);
    }
  });
}

}  // namespace lidarcal::pipeline
