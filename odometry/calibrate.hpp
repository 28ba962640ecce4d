// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Simultaneous calibration of a differential-drive robot's odometry (wheel radii, axle) and its
// laser's mounting (Censi et al. 2013), as the published results were produced:
//   1. fit the closed form on all samples (closed_form.hpp);
//   2. trim the samples above the 99th percentile of disagreement in translation or rotation and
//      refit, 4 times (trimming.hpp); the estimate is the last fit;
//   3. covariance: the inverse Fisher information (covariance.hpp) over the samples that survive
//      one more round of trimming, with the residual variances of the estimate over the samples
//      kept after the first round.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "common/odometry_sample.hpp"
#include "common/status.hpp"
#include "odometry/motion_model.hpp"
#include "odometry/settings.hpp"

namespace lidarcal::odometry {

struct OdometryResult {
  /// ok, or why the data give no estimate: too_few_samples, degenerate_motion, negative_axle
  Status status;
  OdometryParameters estimate;  ///< the last fit (meaningful when ok)
  /// of the estimate, order (r_L, r_R, b, l_x, l_y, l_theta); units of the parameters squared
  Matrix6 covariance = Matrix6::Zero();
  /// residual standard deviations behind the covariance: x, y (m), theta (rad)
  Eigen::Vector3d residual_sigma = Eigen::Vector3d::Zero();
  std::size_t samples_total = 0;          ///< samples given
  std::size_t samples_used = 0;           ///< samples in the last fit
  std::size_t samples_trimmed = 0;        ///< samples dropped by the trimming rounds
  std::size_t samples_in_covariance = 0;  ///< samples whose information makes the covariance
  int fits = 0;                           ///< closed-form fits computed (rounds run + 1)

  bool ok() const { return status.ok(); }
  Vector6 standardErrors() const;  ///< square roots of the covariance's diagonal
};

/// Calibrates from `samples` (in any order). Never throws on data: a failure is a status.
/// Throws InputError for invalid settings.
OdometryResult calibrateOdometry(const std::vector<OdometrySample>& samples,
                                 const OdometrySettings& settings = {});

}  // namespace lidarcal::odometry
