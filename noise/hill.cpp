#include "noise/hill.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/errors.hpp"
#include "common/rng.hpp"

namespace lidarcal::noise {

void HillClimbConfig::validate() const {
  if (!(step > 0.0) || !std::isfinite(step)) throw InputError("", "step", "must be positive", "the seed uses 0.01");
  if (max_jumps < 0) throw InputError("", "max_jumps", "must not be negative", "the seed uses 5");
  if (jump_steps < 1) throw InputError("", "jump_steps", "must be at least 1");
  if (max_evaluations < 1) throw InputError("", "max_evaluations", "must be at least 1");
}

void KlHillConfig::validate() const {
  objective.filter.validate();
  climb.validate();
  if (!(min_variance > 0.0)) throw InputError("", "min_variance", "must be positive");
}

HillClimbResult hillClimb(const std::function<double(const std::vector<double>&)>& objective,
                          const std::vector<double>& start, const std::vector<double>& lower,
                          const HillClimbConfig& config, std::mt19937_64& rng,
                          const std::function<void(int, double)>& on_evaluation) {
  config.validate();
  // Points live on the lattice start + step * index (integers), so a point reached along two
  // paths is the same point bit for bit (no drift of repeated additions).
  const std::size_t n = start.size();
  using Index = std::vector<long long>;
  auto at = [&](const Index& idx) {
    std::vector<double> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = start[i] + config.step * static_cast<double>(idx[i]);
    return x;
  };
  auto lowest = [&](std::size_t i) {  // smallest index whose value is >= lower[i]
    if (!std::isfinite(lower[i])) return std::numeric_limits<long long>::min();
    return static_cast<long long>(std::ceil((lower[i] - start[i]) / config.step - 1e-9));
  };
  HillClimbResult r;
  r.best_value = std::numeric_limits<double>::infinity();
  Index best_idx(n, 0);
  for (std::size_t i = 0; i < n; ++i) best_idx[i] = std::max(best_idx[i], lowest(i));

  auto evaluate = [&](const Index& idx, bool jump) {
    const std::vector<double> x = at(idx);
    const double v = objective(x);
    ++r.evaluations;
    if (v < r.best_value) {
      r.best_value = v;
      r.best = x;
      best_idx = idx;
    }
    r.trace.push_back(HillClimbRecord{v, r.best_value, r.best, jump});
    if (on_evaluation) on_evaluation(r.evaluations, r.best_value);
    return v;
  };

  Index current = best_idx;
  double current_value = evaluate(current, false);
  int jumps_in_a_row = 0;
  std::uniform_int_distribution<int> offset(-config.jump_steps, config.jump_steps);
  while (r.evaluations < config.max_evaluations) {
    ++r.sweeps;
    const double best_before = r.best_value;
    bool moved = false;
    // Seed 003 ch. 3.4: neighbours value +- step of every parameter, accepted when better.
    for (std::size_t i = 0; i < n && r.evaluations < config.max_evaluations; ++i) {
      for (const int dir : {+1, -1}) {
        if (r.evaluations >= config.max_evaluations) break;
        Index candidate = current;
        candidate[i] += dir;
        if (candidate[i] < lowest(i)) continue;
        const double v = evaluate(candidate, false);
        if (v < current_value) {
          current = std::move(candidate);
          current_value = v;
          moved = true;
        }
      }
    }
    if (r.best_value < best_before) jumps_in_a_row = 0;
    if (moved) continue;
    // Stuck: random jump from the best point, unless max_jumps jumps in a row gave nothing.
    if (jumps_in_a_row >= config.max_jumps) {
      r.converged = true;
      break;
    }
    if (r.evaluations >= config.max_evaluations) break;
    ++jumps_in_a_row;
    ++r.jumps;
    current = best_idx;
    for (std::size_t i = 0; i < n; ++i) current[i] = std::max(lowest(i), current[i] + offset(rng));
    current_value = evaluate(current, true);
    if (current_value < best_before) jumps_in_a_row = 0;
  }
  return r;
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

NoiseSetting unpackNoise(const std::vector<double>& x, const NoiseSetting& base, const KlHillConfig& config) {
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

KlHillResult estimateNoiseKlHill(const NoiseProblem& problem, const NoiseSetting& initial, const KlHillConfig& config,
                                 std::uint64_t seed, const std::function<void(int, double)>& on_evaluation) {
  config.validate();
  if (static_cast<int>(initial.sensors.size()) != problem.sensors)
    throw InputError("", "initial noise", "lists " + std::to_string(initial.sensors.size()) + " sensors, the data " +
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
    return evaluateKlObjective(problem, unpackNoise(x, initial, config), config.objective, seed, evaluation++).total;
  };
  auto rng = makeRng(seed, 0);
  result.climb = hillClimb(objective, packNoise(initial, config), lower, config.climb, rng, on_evaluation);
  result.noise = unpackNoise(result.climb.best, initial, config);
  // Objective parts at the best point, re-evaluated on the common stream (deterministic).
  result.at_best = evaluateKlObjective(problem, result.noise, config.objective, seed, 0);
  return result;
}

}  // namespace lidarcal::noise
