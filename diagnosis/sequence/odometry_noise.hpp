// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A continuous recording's odometry noise, from its own steps: the factors on the motion prior's
// default standard deviations that the baseline's steps show. Internal to the diagnosis library.

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/pose2.hpp"
#include "diagnosis/sequence/refits.hpp"

namespace lidarcal::diagnosis::sequence {

/// The factors on the motion prior's standard deviations (translation, heading) that the steps of
/// a fit under it show, robustly: each normalised residual squared over its expected value at the
/// prior's own noise, 1 - S_ii (S the step's leverage: the poses are fitted to the steps too), the
/// median of those over the median of chi-squared with one degree of freedom (0.4549), the square
/// root; the translation's two coordinates pooled. The median, not the mean: a few steps in another
/// optimum would inflate the mean (docs/results/hidden-effects.md, Robots that never stop).
/// Counts: the residuals behind each factor (relative standard error about sqrt(1.36 / count), the
/// median absolute deviation's as an estimate of a normal's scale). Steps whose poses the readings
/// do not both locate are left out; factors 1 and counts 0 with fewer than 10 steps.
struct OdometryNoiseFactors {
  /// factor on the prior's translation standard deviation (1: the default)
  double translation = 1.0;
  double heading = 1.0;  ///< factor on the prior's heading standard deviation (1: the default)
  double translation_count = 0.0;  ///< residuals behind the translation factor
  double heading_count = 0.0;      ///< residuals behind the heading factor
  /// the steps' mean S_ii: near 1, the poses follow the steps and their residuals say little
  double leverage = 0.0;
  bool fitted = false;  ///< fitOdometryNoise kept them (otherwise the prior's defaults stand)
  double translationSe() const {
    return translation * std::sqrt(1.36 / std::max(translation_count, 1.0));
  }
  double headingSe() const { return heading * std::sqrt(1.36 / std::max(heading_count, 1.0)); }
};

OdometryNoiseFactors odometryNoiseFactors(const LandmarkObservations& obs, const JointResult& fit,
                                          const JointConfig& cfg);

/// The median length of the commanded steps between consecutive poses (0 with none).
double medianStepLength(const std::vector<Pose2>& commanded);

}  // namespace lidarcal::diagnosis::sequence
