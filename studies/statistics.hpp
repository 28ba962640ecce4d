// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Per-cell statistics of a Monte Carlo study: quartiles and means of each per-trial metric with
// their Monte Carlo standard errors, order-selection counts under each order rule, and the bias
// and variance of the landmark position estimators (Alhashimi et al. 2021 Figs. 7-8) over every
// (trial, landmark) sample of the cell.

#include <array>
#include <cstddef>
#include <vector>

#include "studies/trial.hpp"

namespace lidarcal::studies {

/// Quartiles of the finite values of a sample (linear interpolation between order statistics,
/// Hyndman & Fan type 7: the default of R and NumPy). NaN when there is no finite value.
struct Quartiles {
  double q25 = 0.0;     ///< first quartile
  double median = 0.0;  ///< median
  double q75 = 0.0;     ///< third quartile
};
Quartiles quartiles(std::vector<double> values);

/// A sample's quartiles, mean and the Monte Carlo uncertainty of both (finite values only).
struct SampleStats {
  std::size_t n = 0;     ///< finite values
  Quartiles q;           ///< quartiles (type 7)
  double mean = 0.0;     ///< mean (the paper plots means over its simulations)
  double mean_se = 0.0;  ///< standard error of the mean, sd / sqrt(n)
  /// Standard error of the median, distribution-free: half the distance between the order
  /// statistics of ranks n/2 -+ sqrt(n)/2 (the median's rank scatters by sqrt(n)/2).
  double median_se = 0.0;
};
SampleStats sampleStats(std::vector<double> values);

/// One estimator's MSE ratios and orders under one order rule.
struct RuleSummary {
  std::array<SampleStats, kTestSets> ratio;  ///< eq. 31 on each test set (TestSet)
  /// trials (with a model) that chose order 0, 1, ..., n_max
  std::vector<std::size_t> order_counts;
};

/// The MSE-ratio metrics of one estimator over a cell's trials.
struct RatioSummary {
  std::size_t runs = 0;      ///< trials the estimator ran in
  std::size_t failures = 0;  ///< of which it returned no model (excluded from the statistics)
  std::array<RuleSummary, kRules> rules;  ///< indexed by Rule
};

/// Landmark position errors of one estimator over a cell's (trial, landmark) samples, in each
/// landmark's radial/tangential frame (trial.hpp, PositionError).
struct PositionSummary {
  std::size_t samples = 0;         ///< landmark estimates scored
  std::size_t missing = 0;         ///< landmarks the estimator did not place (excluded)
  double mean_radial_m = 0.0;      ///< mean radial error, metres
  double mean_tangential_m = 0.0;  ///< mean tangential error, metres
  double bias_m = 0.0;             ///< length of the mean error vector, metres
  double variance_m2 = 0.0;        ///< trace of the error covariance (sample, n - 1), m^2
  double rmse_m = 0.0;             ///< root mean squared error length, metres
  Quartiles error_m;               ///< length of the error vector, metres
  Quartiles radial_m;              ///< radial error, metres
};

/// Position estimators of Figs. 7-8: the paper's triangulation and the joint refinement's centres.
enum class PositionEstimator { triangulation = 0, joint = 1 };
constexpr std::size_t kPositionEstimators = 2;
const char* toString(PositionEstimator e);

struct CellSummary {
  Cell cell;                                    ///< the parameters
  std::size_t trials = 0;                       ///< trials run
  std::array<RatioSummary, kEstimators> ratio;  ///< indexed by Estimator
  std::array<SampleStats, kTestSets> ceiling;   ///< eq. 31 with the true sensor model, per test set
  std::array<PositionSummary, kPositionEstimators> position;  ///< indexed by PositionEstimator
  /// mean landmarks matched per trial (scan level; L at the landmark level)
  double detected_landmarks = 0.0;
};

/// Summarises one cell's trials, in trial order (the result does not depend on how they were run).
CellSummary summarize(const Cell& cell, const std::vector<TrialResult>& trials, int max_order);

}  // namespace lidarcal::studies
