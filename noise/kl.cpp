// SPDX-License-Identifier: BSD-3-Clause
#include "noise/kl.hpp"

#include <cmath>
#include <limits>

namespace lidarcal::noise {

double gaussianKl(double mean_p, double var_p, double mean_q, double var_q) {
  if (!(var_p > 0.0) || !(var_q > 0.0)) return std::numeric_limits<double>::infinity();
  const double d = mean_p - mean_q;
  return 0.5 * (std::log(var_q / var_p) + (var_p + d * d) / var_q - 1.0);
}

KlObjectiveConfig KlObjectiveConfig::faithful() {
  KlObjectiveConfig c;
  c.common_random_numbers = false;
  c.scale = KlScale::variance_as_scale;
  c.statistic = ErrorStatistic::squared_errors;
  c.filter.skip_initialising = false;
  return c;
}

KlObjectiveConfig KlObjectiveConfig::sound() {
  KlObjectiveConfig c;
  c.common_random_numbers = true;
  c.scale = KlScale::variance;
  c.statistic = ErrorStatistic::central;
  c.filter.skip_initialising = true;
  return c;
}

ErrorGaussian fitErrors(const std::vector<double>& e, const std::vector<double>& e2,
                        ErrorStatistic statistic) {
  ErrorGaussian g;
  if (e.empty()) return g;
  const double n = static_cast<double>(e.size());
  for (double v : e) g.mean += v;
  g.mean /= n;
  if (statistic == ErrorStatistic::squared_errors) {
    for (double v : e2) g.var += v;
    g.var /= n;
  } else {
    for (double v : e) g.var += (v - g.mean) * (v - g.mean);
    g.var /= n;
  }
  return g;
}

KlEvaluation evaluateKlObjective(const NoiseProblem& problem, const NoiseSetting& assumed,
                                 const KlObjectiveConfig& config, std::uint64_t seed,
                                 std::uint64_t evaluation) {
  const std::uint64_t stream = config.common_random_numbers ? 1 : 2 + evaluation;
  const FastSlamResult filter = runFastSlam(problem, assumed, config.filter, seed, stream);
  KlEvaluation out;
  out.log_evidence = filter.log_evidence;
  // A (mean, var) pair as a Gaussian's variance: var itself, or var used as the std. dev.
  auto asVariance = [&](double v) { return config.scale == KlScale::variance ? v : v * v; };
  for (int s = 0; s < problem.sensors; ++s) {
    const SensorErrorSamples& e = filter.errors[static_cast<std::size_t>(s)];
    const SensorNoise& a = assumed.sensors[static_cast<std::size_t>(s)];
    const ErrorGaussian pr = fitErrors(e.range_m, e.range_sq_m2, config.statistic);
    const ErrorGaussian pb = fitErrors(e.bearing_rad, e.bearing_sq_rad2, config.statistic);
    // Sharma 2020 ch. 3.3: KL(assumed || predicted), summed over sensors (and here components).
    const double kr =
        gaussianKl(a.range_mean_m, asVariance(a.range_var_m2), pr.mean, asVariance(pr.var));
    const double kb =
        gaussianKl(a.bearing_mean_rad, asVariance(a.bearing_var_rad2), pb.mean, asVariance(pb.var));
    out.predicted_range.push_back(pr);
    out.predicted_bearing.push_back(pb);
    out.kl_range.push_back(kr);
    out.kl_bearing.push_back(kb);
    out.total += kr + kb;
  }
  return out;
}

}  // namespace lidarcal::noise
