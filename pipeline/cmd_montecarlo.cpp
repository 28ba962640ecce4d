// lidarcal montecarlo --study fig7|fig8|fig9|fig10|fig11|all --trials N --out DIR: the Monte Carlo
// study of seed 000 (sections 4.1-4.2, Figs. 7-11) with the paper's closed form, our joint
// refinement and the oracle side by side. Writes DIR/<fig>.csv, <fig>.gp, <fig>.png, <fig>.md and
// DIR/summary.md. Interrupting (Ctrl-C) stops after the trials in progress and writes nothing; a
// plot gnuplot cannot draw fails the command (nothing written); without gnuplot the plots are skipped
// and the command says so.

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <memory>
#include <thread>

#include <CLI/CLI.hpp>
#include <glog/logging.h>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "pipeline/words.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/gnuplot.hpp"
#include "pipeline/progress.hpp"
#include "studies/study.hpp"

namespace lidarcal::pipeline {
namespace {

struct MonteCarloOptions {
  std::string study = "all";
  std::string out;
  std::size_t trials = 0;        // 0: default of the level
  std::size_t joint_trials = 0;  // 0: default of the level
  bool no_joint = false;
  int threads = 0;               // 0: all cores
  std::uint64_t seed = 1;
  std::string level = "landmark";
  std::string angle_noise = "heading";
  std::string noise_law = "paper";
  double max_distance_m = 4.0;   // landmarks' farthest surface from any stop
  double range_max_m = 6.0;      // the sensor's reading window, upper end
  int scans_per_stop = 10;
  int stops = 20;
  double step_m = 0.15;
  int max_order = 3;
  double noise_scale = -1.0;     // < 0: default of the level
  bool quick = false;
  bool overwrite = false;
};

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

std::vector<studies::Figure> figuresOf(const std::string& name) {
  if (name == "all") return studies::allFigures();
  studies::Figure f;
  if (!studies::parseFigure(name, f))
    throw InputError("", "--study", "unknown study '" + name + "'", "use fig7, fig8, fig9, fig10, fig11 or all");
  return {f};
}

/// Runs every figure's gnuplot script in `dir`. A missing gnuplot is reported (the returned text,
/// empty when every plot was drawn); a script that fails is an error: the command fails and writes
/// nothing, rather than leave a partial picture behind (gnuplot stops at the first failing panel).
std::string drawPlots(const std::filesystem::path& dir, const std::vector<std::string>& scripts) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0)
    return "skipped, gnuplot is not installed (apt-get install gnuplot-nox); run gnuplot on the .gp files later";
  for (const auto& script : scripts) {
    std::string why;
    if (!runGnuplot(dir, script, &why)) {
      std::ifstream in(dir / "gnuplot.log");  // gnuplot's own messages, kept by runGnuplot on failure
      std::string log((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (log.size() > 2000) log = log.substr(0, 2000) + "...";
      throw std::runtime_error("montecarlo: gnuplot failed on " + script + ", nothing was written:\n" + log);
    }
  }
  return "";
}

/// Returns false when interrupted (nothing written).
bool runMonteCarlo(const MonteCarloOptions& o) {
  const auto figures = figuresOf(o.study);
  studies::TrialConfig config;
  if (!studies::parseLevel(o.level, config.level))
    throw InputError("", "--level", "unknown level '" + o.level + "'", "use landmark or scan");
  const bool scan = config.level == studies::Level::scan;
  if (!studies::parseAngleNoise(o.angle_noise, config.angle_noise))
    throw InputError("", "--angle-noise", "unknown model '" + o.angle_noise + "'", "use heading, beams or bearing");
  if (!studies::parseNoiseLaw(o.noise_law, config.noise_law))
    throw InputError("", "--noise-law", "unknown law '" + o.noise_law + "'", "use paper or squared");
  if (scan && config.angle_noise != studies::AngleNoise::heading)
    throw InputError("", "--angle-noise", "the scan level models the angle noise as heading noise only",
                     "drop --angle-noise or use heading");
  config.path.scans_per_stop = o.scans_per_stop;
  config.path.stops = o.stops;
  config.path.step_m = o.step_m;
  config.max_order = o.max_order;
  config.placement.max_surface_m = o.max_distance_m;
  config.sensor.range_max_m = o.range_max_m;
  config.noise_scale = o.noise_scale >= 0.0 ? o.noise_scale : (scan ? 0.2 : 1.0);
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError("", "options", e.what());
  }
  const studies::StudyGrids grids = o.quick ? studies::StudyGrids::quick() : studies::StudyGrids{};

  studies::RunOptions run;
  // Defaults: the landmark level runs the paper's 1000 trials (100 with --quick), the joint
  // refinement on the first 200 (10); the scan level 100 trials (10), the joint on the first 50 (5).
  run.trials = o.trials ? o.trials : (scan ? (o.quick ? 10 : 100) : (o.quick ? 100 : 1000));
  run.joint_trials = o.no_joint ? 0 : (o.joint_trials ? o.joint_trials : (scan ? (o.quick ? 5 : 50) : (o.quick ? 10 : 200)));
  run.joint_trials = std::min(run.joint_trials, run.trials);
  run.threads = o.threads > 0 ? o.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  run.seed = o.seed;
  run.stop = &g_interrupted;

  // From here to the commit a SIGINT only sets the flag: the trials stop, nothing is committed.
  g_interrupted = false;
  InterruptGuard guard;
  // Ceres logs through glog when a solve struggles (WARNING: a step failed and is retried with more
  // damping; ERROR: the solve gave up, and the estimator either reports a failure, counted in the
  // CSV's *_failed columns, or goes on from its last usable solution). Over thousands of trials
  // these lines would bury the progress bar.
  FLAGS_minloglevel = std::max(FLAGS_minloglevel, static_cast<int>(google::GLOG_FATAL));
  io::StagedDirectory out(o.out, o.overwrite);
  const auto cells = studies::studyCells(figures, grids);
  if (!quiet())
    std::fprintf(stderr, "montecarlo: %zu cells x %zu trials (joint refinement on %zu), %s level, %s\n",
                 cells.size(), run.trials, run.joint_trials, studies::toString(config.level),
                 plural(static_cast<std::size_t>(run.threads), "thread").c_str());
  const auto start = std::chrono::steady_clock::now();
  studies::StudyOutput result;
  {
    Progress progress("montecarlo", cells.size() * run.trials);
    run.on_progress = [&](std::size_t done, std::size_t) { progress.update(done); };
    result = studies::runStudy(figures, grids, config, run);
    if (!result.interrupted) progress.finish();
  }
  if (result.interrupted) return false;  // `out` is discarded: nothing is written
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  for (const auto& [name, text] : result.files) io::writeTextAtomically(out.path() / name, text);
  const std::string plots = drawPlots(out.path(), result.gnuplot_scripts);
  if (g_interrupted) return false;
  out.commit();
  const double trials = static_cast<double>(cells.size() * run.trials);
  std::printf("Monte Carlo study: %zu cells x %zu trials in %.1f s (%.1f trials/s, %s)\n", cells.size(), run.trials,
              seconds, trials / seconds, plural(static_cast<std::size_t>(run.threads), "thread").c_str());
  std::printf("Output: %s (summary.md; per figure .csv, .png, .gp, .md)\n", o.out.c_str());
  if (!plots.empty()) std::printf("Plots: %s\n", plots.c_str());
  return true;
}

}  // namespace

void addMonteCarloCommand(CLI::App& app) {
  auto o = std::make_shared<MonteCarloOptions>();
  CLI::App* sub = app.add_subcommand(
      "montecarlo",
      "Monte Carlo study of Alhashimi et al. 2021 (Figs. 7-11): the paper's closed form, the joint refinement and the oracle "
      "over noise levels and landmark counts. Ctrl-C stops cleanly and writes nothing (OUT appears only when "
      "complete).");
  sub->add_option("--study", o->study, "fig7, fig8, fig9, fig10, fig11 or all")->capture_default_str();
  sub->add_option("-o,--out", o->out, "Output directory (created whole at the end; see docs/FORMAT.md)")->required();
  sub->add_option("--trials", o->trials,
                  "Trials per cell (default 1000 at the landmark level, 100 at the scan level; --quick: 100 / 10)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--joint-trials", o->joint_trials,
                  "Run the joint refinement on the first N trials of each cell (default 200 landmark level, 50 scan "
                  "level; --quick: 10 / 5)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--no-joint", o->no_joint, "Skip the joint refinement");
  sub->add_option("--threads", o->threads, "Worker threads (default: all cores); the output does not depend on it")
      ->check(CLI::PositiveNumber);
  sub->add_option("--seed", o->seed, "Study seed; the same seed and options give the same bytes")->capture_default_str();
  sub->add_option("--level", o->level,
                  "landmark: Alhashimi et al. 2021 eqs. 3, 5, 8 with beams ray-cast on each landmark (fast); scan: whole scans "
                  "ray-cast and the detector in the loop")
      ->capture_default_str();
  sub->add_option("--angle-noise", o->angle_noise,
                  "What sigma_theta perturbs: heading (the robot's heading at each stop: every beam of the stop "
                  "turns; default, the scan level's only model), beams (eq. 5: each landmark's centre bearing and "
                  "beam angles at each stop) or bearing (eq. 5 on the centre bearing only: the joint refinement, "
                  "which fits beam angles, does not see it)")
      ->capture_default_str();
  sub->add_option("--noise-law", o->noise_law,
                  "Simulated range noise: paper (Alhashimi et al. 2021: 5 % of f(d)) or squared (Alhashimi et al. 2016: sigma_e f(d)^2, the "
                  "same at 3 m)")
      ->capture_default_str();
  sub->add_option("--max-distance", o->max_distance_m,
                  "Farthest landmark surface from any stop, metres (Alhashimi et al. 2021, section 4.3, keeps them within 5 m)")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 100.0));
  sub->add_option("--range-max", o->range_max_m, "Upper end of the sensor's reading window, metres")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  sub->add_option("--scans-per-stop", o->scans_per_stop, "Scans averaged at each stop")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub->add_option("--stops", o->stops, "Stops along the path")->capture_default_str()->check(CLI::Range(3, 1000));
  sub->add_option("--step", o->step_m, "Distance between stops, metres")->capture_default_str()->check(CLI::PositiveNumber);
  sub->add_option("--max-order", o->max_order, "Highest polynomial order tried (n_max)")
      ->capture_default_str()
      ->check(CLI::Range(1, 6));
  sub->add_option("--noise-scale", o->noise_scale,
                  "Multiplies the paper's range noise (beta = 0.05 alpha); default 1 at the landmark level, 0.2 at "
                  "the scan level (the detector cannot find the poles through the paper's noise)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--quick", o->quick, "Coarse grids and fewer trials, for a first look");
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  sub->callback([o] {
    if (!runMonteCarlo(*o)) {
      std::fprintf(stderr, "\nlidarcal: montecarlo interrupted; nothing was written\n");
      std::exit(130);
    }
  });
}

}  // namespace lidarcal::pipeline
