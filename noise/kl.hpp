// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The noise-consistency objective of Sharma 2020 (ch. 3.2-3.3): run the particle filter under an
// assumed noise setting, fit a Gaussian to each sensor's predicted errors per component (range,
// bearing), and sum the KL divergences KL(assumed || predicted) over sensors and components.
//
// Three switches select the seed's variant or ours (docs/results/noise-consistency.md):
//  - common random numbers: the same particle-filter random stream for every candidate setting
//    (ours), or a fresh stream per evaluation (seed: the objective is then a noisy function);
//  - KL scale: the Gaussians parametrised by their variance (ours) or with the variance value used
//    as the standard deviation (seed: KL between "standard deviations");
//  - error statistic: central moments of the weighted errors (ours) or the mean of the particle-
//    weighted squared errors about zero as the variance (seed: squared errors, so a bias leaks
//    into the variance).

#include <cstdint>
#include <vector>

#include "common/observation.hpp"
#include "noise/fastslam.hpp"
#include "noise/problem.hpp"

namespace lidarcal::noise {

/// KL(p || q) of univariate Gaussians given by mean and variance, nats (closed form):
///   1/2 [ log(var_q / var_p) + (var_p + (mean_p - mean_q)^2) / var_q - 1 ].
/// +infinity when a variance is not positive.
double gaussianKl(double mean_p, double var_p, double mean_q, double var_q);

enum class KlScale {
  variance,           ///< N(mean, var): KL between variances (ours)
  variance_as_scale,  ///< N(mean, var^2): the variance value used as the standard deviation (seed)
};
enum class ErrorStatistic {
  central,  ///< mean and central variance of the weighted mean errors (ours)
  /// mean of the weighted mean errors; variance = mean weighted squared error about 0 (seed)
  squared_errors,
};

struct KlObjectiveConfig {
  FastSlamConfig filter;              ///< particle filter (80 particles, seed ch. 5)
  bool common_random_numbers = true;  ///< same filter stream for every evaluation
  KlScale scale = KlScale::variance;  ///< how a (mean, var) pair becomes a Gaussian
  ErrorStatistic statistic = ErrorStatistic::central;  ///< how the predicted Gaussian is fitted

  /// The seed's variant: no common random numbers, variance as scale, squared errors, every
  /// reading counted.
  static KlObjectiveConfig faithful();
  /// Ours: common random numbers, variances, central statistics, initialising readings left out.
  static KlObjectiveConfig sound();
};

/// A Gaussian fitted to one component of one sensor's predicted errors.
struct ErrorGaussian {
  double mean = 0.0;  ///< metres or radians
  double var = 0.0;   ///< m^2 or rad^2
};

/// The objective at one noise setting, with its parts.
struct KlEvaluation {
  double total = 0.0;                            ///< sum of KL over sensors and components, nats
  std::vector<ErrorGaussian> predicted_range;    ///< per sensor
  std::vector<ErrorGaussian> predicted_bearing;  ///< per sensor
  std::vector<double> kl_range;                  ///< per sensor, nats
  std::vector<double> kl_bearing;                ///< per sensor, nats
  double log_evidence = 0.0;                     ///< the filter's log marginal likelihood, nats
};

/// Fits the predicted Gaussian of one component to weighted mean errors `e` and weighted mean
/// squared errors `e2` (same length) with `statistic`.
ErrorGaussian fitErrors(const std::vector<double>& e, const std::vector<double>& e2,
                        ErrorStatistic statistic);

/// Evaluates the objective at `assumed`. The filter stream is `1` with common random numbers,
/// `2 + evaluation` without, under base `seed`.
KlEvaluation evaluateKlObjective(const NoiseProblem& problem, const NoiseSetting& assumed,
                                 const KlObjectiveConfig& config, std::uint64_t seed,
                                 std::uint64_t evaluation);

}  // namespace lidarcal::noise
