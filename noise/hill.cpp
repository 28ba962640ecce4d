// SPDX-License-Identifier: BSD-3-Clause
#include "noise/hill.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/errors.hpp"
#include "common/rng.hpp"

namespace lidarcal::noise {

void HillClimbConfig::validate() const {
  if (!(step > 0.0) || !std::isfinite(step))
    throw InputError("", "step", "must be positive", "the seed uses 0.01");
  if (max_jumps < 0) throw InputError("", "max_jumps", "must not be negative", "the seed uses 5");
  if (jump_steps < 1) throw InputError("", "jump_steps", "must be at least 1");
  if (max_evaluations < 1) throw InputError("", "max_evaluations", "must be at least 1");
}

void KlHillConfig::validate() const {
  objective.filter.validate();
  climb.validate();
  if (!(min_variance > 0.0)) throw InputError("", "min_variance", "must be positive");
}

namespace {

/// Hill climbing on the lattice start + step * index (integers), so a point reached along two
/// paths is the same point bit for bit (no drift of repeated additions).
class LatticeClimber {
 public:
  using Index = std::vector<long long>;
  LatticeClimber(const std::function<double(const std::vector<double>&)>& objective,
                 const std::vector<double>& start, const std::vector<double>& lower,
                 const HillClimbConfig& config,
                 const std::function<void(int, double)>& on_evaluation)
      : objective_(objective),
        start_(start),
        lower_(lower),
        config_(config),
        on_evaluation_(on_evaluation),
        n_(start.size()) {}
  HillClimbResult run(std::mt19937_64& rng);

 private:
  std::vector<double> at(const Index& idx) const;
  long long lowest(std::size_t i) const;
  double evaluate(const Index& idx, bool jump);
  bool sweep();
  bool budgetLeft() const { return r_.evaluations < config_.max_evaluations; }

  const std::function<double(const std::vector<double>&)>& objective_;
  const std::vector<double>& start_;
  const std::vector<double>& lower_;
  const HillClimbConfig& config_;
  const std::function<void(int, double)>& on_evaluation_;
  const std::size_t n_;
  HillClimbResult r_;
  Index best_idx_, current_;
  double current_value_ = 0.0;
};

std::vector<double> LatticeClimber::at(const Index& idx) const {
  std::vector<double> x(n_);
  for (std::size_t i = 0; i < n_; ++i)
    x[i] = start_[i] + config_.step * static_cast<double>(idx[i]);
  return x;
}

/// Smallest index whose value is >= lower[i].
long long LatticeClimber::lowest(std::size_t i) const {
  if (!std::isfinite(lower_[i])) return std::numeric_limits<long long>::min();
  return static_cast<long long>(std::ceil((lower_[i] - start_[i]) / config_.step - 1e-9));
}

double LatticeClimber::evaluate(const Index& idx, bool jump) {
  const std::vector<double> x = at(idx);
  const double v = objective_(x);
  ++r_.evaluations;
  if (v < r_.best_value) {
    r_.best_value = v;
    r_.best = x;
    best_idx_ = idx;
  }
  r_.trace.push_back(HillClimbRecord{v, r_.best_value, r_.best, jump});
  if (on_evaluation_) on_evaluation_(r_.evaluations, r_.best_value);
  return v;
}

/// Sharma 2020 ch. 3.4: neighbours value +- step of every parameter, accepted when better; true
/// when the current point moved.
bool LatticeClimber::sweep() {
  bool moved = false;
  for (std::size_t i = 0; i < n_ && budgetLeft(); ++i) {
    for (const int dir : {+1, -1}) {
      if (!budgetLeft()) break;
      Index candidate = current_;
      candidate[i] += dir;
      if (candidate[i] < lowest(i)) continue;
      const double v = evaluate(candidate, false);
      if (v < current_value_) {
        current_ = std::move(candidate);
        current_value_ = v;
        moved = true;
      }
    }
  }
  return moved;
}

HillClimbResult LatticeClimber::run(std::mt19937_64& rng) {
  r_.best_value = std::numeric_limits<double>::infinity();
  best_idx_.assign(n_, 0);
  for (std::size_t i = 0; i < n_; ++i) best_idx_[i] = std::max(best_idx_[i], lowest(i));
  current_ = best_idx_;
  current_value_ = evaluate(current_, false);
  int jumps_in_a_row = 0;
  std::uniform_int_distribution<int> offset(-config_.jump_steps, config_.jump_steps);
  while (budgetLeft()) {
    ++r_.sweeps;
    const double best_before = r_.best_value;
    const bool moved = sweep();
    if (r_.best_value < best_before) jumps_in_a_row = 0;
    if (moved) continue;
    // Stuck: random jump from the best point, unless max_jumps jumps in a row gave nothing.
    if (jumps_in_a_row >= config_.max_jumps) {
      r_.converged = true;
      break;
    }
    if (!budgetLeft()) break;
    ++jumps_in_a_row;
    ++r_.jumps;
    current_ = best_idx_;
    for (std::size_t i = 0; i < n_; ++i)
      current_[i] = std::max(lowest(i), current_[i] + offset(rng));
    current_value_ = evaluate(current_, true);
    if (current_value_ < best_before) jumps_in_a_row = 0;
  }
  return std::move(r_);
}

}  // namespace

HillClimbResult hillClimb(const std::function<double(const std::vector<double>&)>& objective,
                          const std::vector<double>& start, const std::vector<double>& lower,
                          const HillClimbConfig& config, std::mt19937_64& rng,
                          const std::function<void(int, double)>& on_evaluation) {
  config.validate();
  return LatticeClimber(objective, start, lower, config, on_evaluation).run(rng);
}

std::vector<double> packNoise(const NoiseSetting& n, const KlHillConfig& config) {
  std::vector<double> x;
  for (const auto& s : n.sensors) {
    if (config.climb_means) x.push_back(s.range_mean_m);
    x.push_back(s.range_var_m2);
    if (config.climb_means) x.push_back(s.bearing_mean_rad);
    x.push_back(s.bearing_var_rad2);
  }
  if (config.climb_process) {
    x.push_back(n.process.dx_var_m2);
    x.push_back(n.process.dy_var_m2);
    x.push_back(n.process.dtheta_var_rad2);
  }
  return x;
}

NoiseSetting unpackNoise(const std::vector<double>& x, const NoiseSetting& base,
                         const KlHillConfig& config) {
  NoiseSetting n = base;
  std::size_t i = 0;
  for (auto& s : n.sensors) {
    if (config.climb_means) s.range_mean_m = x[i++];
    s.range_var_m2 = x[i++];
    if (config.climb_means) s.bearing_mean_rad = x[i++];
    s.bearing_var_rad2 = x[i++];
  }
  if (config.climb_process) {
    n.process.dx_var_m2 = x[i++];
    n.process.dy_var_m2 = x[i++];
    n.process.dtheta_var_rad2 = x[i++];
  }
  return n;
}

KlHillResult estimateNoiseKlHill(const NoiseProblem& problem, const NoiseSetting& initial,
                                 const KlHillConfig& config, std::uint64_t seed,
                                 const std::function<void(int, double)>& on_evaluation) {
  config.validate();
  if (static_cast<int>(initial.sensors.size()) != problem.sensors)
    throw InputError("", "initial noise",
                     "lists " + std::to_string(initial.sensors.size()) + " sensors, the data " +
                         std::to_string(problem.sensors),
                     "give one entry per sensor in --init");
  KlHillResult result;
  std::vector<double> lower;
  const double no_bound = -std::numeric_limits<double>::infinity();
  for (int s = 0; s < problem.sensors; ++s) {
    const std::string p = "s" + std::to_string(s) + ".";
    if (config.climb_means) {
      result.parameter_names.push_back(p + "range_mean_m");
      lower.push_back(no_bound);
    }
    result.parameter_names.push_back(p + "range_var_m2");
    lower.push_back(config.min_variance);
    if (config.climb_means) {
      result.parameter_names.push_back(p + "bearing_mean_rad");
      lower.push_back(no_bound);
    }
    result.parameter_names.push_back(p + "bearing_var_rad2");
    lower.push_back(config.min_variance);
  }
  if (config.climb_process)
    for (const char* name : {"process.dx_m2", "process.dy_m2", "process.dtheta_rad2"}) {
      result.parameter_names.push_back(name);
      lower.push_back(0.0);
    }

  std::uint64_t evaluation = 0;
  auto objective = [&](const std::vector<double>& x) {
    return evaluateKlObjective(problem, unpackNoise(x, initial, config), config.objective, seed,
                               evaluation++)
        .total;
  };
  auto rng = makeRng(seed, 0);
  result.climb =
      hillClimb(objective, packNoise(initial, config), lower, config.climb, rng, on_evaluation);
  result.noise = unpackNoise(result.climb.best, initial, config);
  // Objective parts at the best point, re-evaluated on the common stream (deterministic).
  result.at_best = evaluateKlObjective(problem, result.noise, config.objective, seed, 0);
  return result;
}

}  // namespace lidarcal::noise
