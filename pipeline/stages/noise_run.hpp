// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Composition of noise estimation for `lidarcal noise-consistency` and the benchmarks: runs the
// KL hill climbing (Sharma 2020) or the ML estimator on a NoiseProblem, times it, turns the result
// into result.json (docs/FORMAT.md) and draws the traces with gnuplot.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "common/observation.hpp"
#include "noise/hill.hpp"
#include "noise/ml.hpp"
#include "noise/problem.hpp"

namespace lidarcal::pipeline {

enum class NoiseMethod { kl_hill, ml };

struct NoiseRunOptions {
  NoiseMethod method = NoiseMethod::ml;  ///< estimator
  bool faithful = false;   ///< kl-hill: label of the objective variant in `kl` (the seed's or ours)
  std::uint64_t seed = 1;  ///< kl-hill: jumps and particle filter streams
  std::optional<NoiseSetting> initial;  ///< starting setting (kl-hill default: defaultInitialNoise)
  /// kl-hill settings (kl.objective: KlObjectiveConfig::faithful() or sound())
  noise::KlHillConfig kl;
  noise::MlNoiseConfig ml;  ///< ml settings (initial set from `initial` when given)
};

/// Starting setting of the hill climbing when none is given: means 0, variances 0.5 (m^2,
/// rad^2), process variances 0.
NoiseSetting defaultInitialNoise(int sensors);

struct NoiseRun {
  NoiseMethod method = NoiseMethod::ml;
  bool faithful = false;
  std::uint64_t seed = 0;
  NoiseSetting noise;              ///< the estimate
  bool process_estimated = false;  ///< process variances estimated (else as assumed)
  std::string status = "ok";       ///< "ok" or "not_converged"
  std::string message;             ///< details when not ok
  /// kl-hill: best KL after each evaluation; ml: -log L per iteration
  std::vector<double> objective_trace;
  int evaluations = 0;  ///< kl-hill: particle-filter runs; ml: adjustments solved
  /// wall time of the estimation (printed, not written: outputs are deterministic)
  double time_s = 0.0;
  std::optional<noise::KlHillResult> kl;   ///< details of a kl-hill run
  std::optional<noise::MlNoiseResult> ml;  ///< details of an ml run
};

/// Runs the chosen estimator. `on_progress(done, total)` reports evaluations (kl-hill) or
/// iterations (ml).
NoiseRun runNoiseEstimation(const noise::NoiseProblem& problem, const NoiseRunOptions& options,
                            const std::function<void(std::size_t, std::size_t)>& on_progress = {});

/// result.json (format lidarcal-noise-result/1). `sensor_labels[i]` names sensor i as
/// observations.csv did (empty: 0..S-1).
nlohmann::ordered_json noiseRunToJson(const NoiseRun& run, const noise::NoiseProblem& problem,
                                      const std::vector<int>& sensor_labels = {});

/// Writes the traces (trace.dat, params.dat) and their PNG plots (objective.png, params.png)
/// into the existing directory `dir`, drawing `truth` as dashed lines when given. Returns an
/// empty string, or why gnuplot failed (the data files are written anyway).
std::string writeNoisePlots(const std::filesystem::path& dir, const NoiseRun& run,
                            const std::optional<NoiseSetting>& truth);

}  // namespace lidarcal::pipeline
