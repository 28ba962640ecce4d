// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Does the stated uncertainty match the scatter? The samples are split into N subsets X_1..X_N,
// each is calibrated on its own, and each parameter's spread across the subsets is set beside
// the mean of the subsets' own standard errors. Consecutive subsets are stretches of the drive;
// a recording made in phases (first turning in place, then pivoting) gives stretches that each
// hold one kind of motion and cannot be calibrated alone: interleaved subsets (every N-th
// sample) keep the recording's mix of motions in each. If the covariance is right, spread / stated
// is near 1; with N subsets the spread is itself uncertain: (N - 1) spread^2 / stated^2 ~
// chi-square with N - 1 degrees of freedom, which gives the ratio's 95 % interval.

#include <cstddef>
#include <vector>

#include "common/odometry_sample.hpp"
#include "common/status.hpp"
#include "odometry/calibrate.hpp"

namespace lidarcal::odometry {

/// How the samples are dealt into subsets.
enum class SubsetSplit {
  consecutive,  ///< X_s holds samples [s n / N, (s + 1) n / N)
  interleaved,  ///< X_s holds the samples i with i mod N = s
};

struct SubsetScatter {
  Status status;  ///< ok when at least two subsets gave an estimate; else too_few_samples
  std::vector<std::size_t> first_sample;  ///< index of each subset's first sample
  std::vector<OdometryResult> subsets;    ///< X_1..X_N, each calibrated alone
  int subsets_ok = 0;                     ///< subsets with an estimate (those counted below)
  Vector6 mean = Vector6::Zero();         ///< mean of the subsets' estimates
  /// standard deviation of the subsets' estimates about their mean (divided by count - 1)
  Vector6 spread = Vector6::Zero();
  Vector6 mean_standard_error = Vector6::Zero();  ///< mean of the subsets' own standard errors
  /// spread / mean_standard_error and its 95 % interval under a correct covariance
  Vector6 ratio = Vector6::Zero(), ratio_low = Vector6::Zero(), ratio_high = Vector6::Zero();
};

/// Splits `samples` (in their order) into `count` subsets of near-equal size and calibrates each
/// with `settings`. `count` must be at least 2.
SubsetScatter scatterOverSubsets(const std::vector<OdometrySample>& samples, int count,
                                 const OdometrySettings& settings = {},
                                 SubsetSplit split = SubsetSplit::consecutive);

}  // namespace lidarcal::odometry
