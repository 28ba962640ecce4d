// SPDX-License-Identifier: BSD-3-Clause
// What sets the MSE ratio's ceiling in the Monte Carlo study (docs/results/montecarlo.md,
// "The ratio's ceiling"): one cell of Fig. 9 (L = 5, sigma_s = 1 cm, sigma_theta = 2
// degrees on the heading), the closed form, the oracle and the ceiling (eq. 31 with the simulated
// sensor's own bias) on the three test sets, while one setting at a time moves from the study's
// default towards the paper's field (Alhashimi et al. 2021 section 4.3: landmarks up to 5 m) and
// beyond: scans averaged per stop, farthest landmark, reading window, noise law. Medians and means
// with their Monte Carlo standard errors.
//   build/bench/montecarlo_ceiling [--trials 500] [--threads 2] [--seed 1]

#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "studies/runner.hpp"
#include "studies/statistics.hpp"

namespace {

using namespace lidarcal;
using namespace lidarcal::studies;

struct Variant {
  std::string name;
  int scans_per_stop = 10;
  double max_surface_m = 4.0;
  double range_max_m = 6.0;
  NoiseLaw law = NoiseLaw::paper;
};

std::string text(const SampleStats& s) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.1f ± %.1f / %.1f ± %.1f", s.q.median, s.median_se, s.mean,
                s.mean_se);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("the MSE ratio's ceiling in the Monte Carlo study");
  RunOptions run;
  run.trials = 500;
  run.joint_trials = 0;
  run.threads = 2;
  app.add_option("--trials", run.trials, "trials per variant");
  app.add_option("--threads", run.threads, "worker threads");
  app.add_option("--seed", run.seed, "study seed");
  CLI11_PARSE(app, argc, argv);
  const std::vector<Variant> variants = {
      {"study default: 10 scans/stop, landmarks to 4 m, window 6 m, noise 5 % of f(d)", 10, 4.0,
       6.0, NoiseLaw::paper},
      {"25 scans/stop", 25, 4.0, 6.0, NoiseLaw::paper},
      {"25 scans/stop, landmarks to 5 m (Alhashimi et al. 2021 section 4.3)", 25, 5.0, 6.0,
       NoiseLaw::paper},
      {"25 scans/stop, landmarks to 5 m, no window", 25, 5.0, 1000.0, NoiseLaw::paper},
      {"25 scans/stop, landmarks to 4 m, Alhashimi et al. 2016's noise law (same at 3 m)", 25, 4.0,
       6.0, NoiseLaw::squared},
      {"25 scans/stop, landmarks to 5 m, Alhashimi et al. 2016's noise law", 25, 5.0, 6.0,
       NoiseLaw::squared},
      {"50 scans/stop, landmarks to 5 m", 50, 5.0, 6.0, NoiseLaw::paper},
      {"100 scans/stop, landmarks to 5 m", 100, 5.0, 6.0, NoiseLaw::paper},
  };
  const Cell cell{5, 0.01, deg2rad(2.0)};
  std::printf(
      "L = %d, sigma_s = %.0f cm, sigma_theta = %.0f degrees on the heading, %zu trials per "
      "variant, seed %llu. "
      "Each cell: median ± its standard error / mean ± its standard error of eq. 31.\n\n",
      cell.landmarks, cell.sigma_s_m * 100.0, rad2deg(cell.sigma_theta_rad), run.trials,
      static_cast<unsigned long long>(run.seed));
  std::vector<CellSummary> summaries;
  for (const Variant& v : variants) {
    TrialConfig config;
    config.path.scans_per_stop = v.scans_per_stop;
    config.placement.max_surface_m = v.max_surface_m;
    config.sensor.range_max_m = v.range_max_m;
    config.noise_law = v.law;
    summaries.push_back(
        summarize(cell, runCells(config, {cell}, run).results[0], config.max_order));
  }
  const char* sets[kTestSets] = {"every beam, averaged per stop", "centre beam, averaged per stop",
                                 "single readings"};
  for (std::size_t set = 0; set < kTestSets; ++set) {
    std::printf(
        "Test set: %s\n\n| variant | closed form (paper) | oracle | ceiling (true model) "
        "|\n|---|---|---|---|\n",
        sets[set]);
    for (std::size_t i = 0; i < variants.size(); ++i) {
      const CellSummary& c = summaries[i];
      const auto& cf =
          c.ratio[static_cast<std::size_t>(Estimator::closed_form)].rules[0].ratio[set];
      const auto& orc = c.ratio[static_cast<std::size_t>(Estimator::oracle)].rules[0].ratio[set];
      std::printf("| %s | %s | %s | %s |\n", variants[i].name.c_str(), text(cf).c_str(),
                  text(orc).c_str(), text(c.ceiling[set]).c_str());
    }
    std::printf("\n");
  }
  return 0;
}
