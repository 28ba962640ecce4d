// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Hill climbing of Sharma 2020 ch. 3.4 and ch. 5, and its use on the noise-consistency objective.
//
// Each parameter has two neighbours (value +- step), so each (mean, variance) pair has the
// seed's four. A sweep visits the neighbours of the current point in parameter order and moves
// to a neighbour as soon as it is better (the seed's traces accept several moves per iteration).
// A sweep without a move is a local minimum: the climber jumps to the best point plus a random
// whole number of steps in [-jump_steps, jump_steps] per parameter and climbs on; after
// `max_jumps` jumps in a row that did not improve the best point it stops (seed: 5 jumps).
// Points live on the lattice start + step * integer, so a point reached along two paths is the
// same point bit for bit (the seed's traces show the drift of repeated additions,
// 0.29900000000000004).

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "common/observation.hpp"
#include "noise/kl.hpp"
#include "noise/problem.hpp"

namespace lidarcal::noise {

struct HillClimbConfig {
  double step = 0.01;  ///< step of every parameter, in its unit (Sharma 2020 ch. 5: 0.01)
  int max_jumps = 5;   ///< random jumps in a row without improvement before stopping (seed: 5)
  /// a jump moves each parameter by up to this many steps (our choice; the seed does not say)
  int jump_steps = 10;
  int max_evaluations = 5000;  ///< hard cap on objective evaluations
  void validate() const;       ///< throws InputError
};

/// One objective evaluation as the climber saw it.
struct HillClimbRecord {
  double value = 0.0;               ///< objective at the evaluated point
  double best_value = 0.0;          ///< best objective so far (never increases)
  std::vector<double> best_params;  ///< best point so far
  bool jump = false;                ///< the point was a random jump
};

struct HillClimbResult {
  std::vector<double> best;            ///< best point found
  double best_value = 0.0;             ///< objective there
  std::vector<HillClimbRecord> trace;  ///< one record per evaluation, in order
  int evaluations = 0;                 ///< objective evaluations
  int sweeps = 0;                      ///< neighbourhood sweeps (the seed's "iterations")
  int jumps = 0;                       ///< random jumps made
  bool converged = false;              ///< stopped by max_jumps (false: hit max_evaluations)
};

/// Minimises `objective` from `start`. `lower[i]` bounds parameter i from below (neighbours and
/// jumps below it are skipped / clamped). `on_evaluation(evaluations, best_value)` is called
/// after every evaluation (progress).
HillClimbResult hillClimb(const std::function<double(const std::vector<double>&)>& objective,
                          const std::vector<double>& start, const std::vector<double>& lower,
                          const HillClimbConfig& config, std::mt19937_64& rng,
                          const std::function<void(int, double)>& on_evaluation = {});

struct KlHillConfig {
  KlObjectiveConfig objective = KlObjectiveConfig::sound();  ///< seed's or our variant
  HillClimbConfig climb;                                     ///< step 0.01, 5 jumps
  bool climb_means = true;  ///< climb the biases too (the seed climbs (mean, var) pairs)
  /// also climb the three process variances (the seed keeps them fixed)
  bool climb_process = false;
  double min_variance = 1e-4;  ///< lowest variance tried, in the variance's unit
  void validate() const;       ///< throws InputError
};

/// Result of noise estimation by KL hill climbing.
struct KlHillResult {
  NoiseSetting noise;     ///< best setting found (process: as assumed unless climbed)
  KlEvaluation at_best;   ///< objective parts at the best setting, re-evaluated as evaluation 0
                          ///< (equal to climb.best_value with common random numbers
                          ///< only)
  HillClimbResult climb;  ///< trace and counts
  /// name of each climbed parameter, e.g. "s0.range_var_m2"
  std::vector<std::string> parameter_names;
};

/// The parameter vector of a setting and back (per sensor: range mean, range var, bearing mean,
/// bearing var; then dx, dy, dtheta variances when climbed; means left out when not climbed).
std::vector<double> packNoise(const NoiseSetting& n, const KlHillConfig& config);
NoiseSetting unpackNoise(const std::vector<double>& x, const NoiseSetting& base,
                         const KlHillConfig& config);

/// Sharma 2020's estimator: hill climbing of the KL noise-consistency objective from `initial`.
/// The jumps draw from stream 0 of `seed`; the filter from streams 1, 2, ... (noise_kl.hpp).
KlHillResult estimateNoiseKlHill(const NoiseProblem& problem, const NoiseSetting& initial,
                                 const KlHillConfig& config, std::uint64_t seed,
                                 const std::function<void(int, double)>& on_evaluation = {});

}  // namespace lidarcal::noise
