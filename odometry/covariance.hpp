// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The covariance of the estimate (Censi et al. 2013): the inverse Fisher information of the six
// parameters, with each sample's scan-matched displacement taken as Gaussian around the
// prediction with a diagonal covariance Sigma = diag(var_x, var_y, var_theta):
//   I = sum_k J_k' Sigma^-1 J_k,   cov = I^-1,
// J_k the Jacobian of the predicted displacement (laser frame) at the estimate. Sigma is the
// residuals' own variance, estimated from the data.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "common/odometry_sample.hpp"
#include "common/status.hpp"
#include "odometry/motion_model.hpp"

namespace lidarcal::odometry {

/// Below this a residual variance is taken as this (m^2 or rad^2): noise-free data give a
/// vanishing but finite covariance.
inline constexpr double kVarianceFloor = 1e-24;

/// Variance (about their mean, divided by n) of the residuals x, y (m^2) and theta (rad^2) of
/// the samples listed in `indices` under `params`. `indices` must not be empty.
Eigen::Vector3d residualVariances(const std::vector<OdometrySample>& samples,
                                  const std::vector<std::size_t>& indices,
                                  const OdometryParameters& params);

struct FisherCovariance {
  Status status;  ///< ok, or degenerate_motion when the information matrix is singular
  /// in the order (r_L, r_R, b, l_x, l_y, l_theta); units of the parameters squared
  Matrix6 covariance = Matrix6::Zero();
};

/// The inverse Fisher information over the samples listed in `indices`, at `params`, with the
/// residual variances `variances` (x, y, theta; floored at kVarianceFloor).
FisherCovariance fisherCovariance(const std::vector<OdometrySample>& samples,
                                  const std::vector<std::size_t>& indices,
                                  const OdometryParameters& params,
                                  const Eigen::Vector3d& variances);

}  // namespace lidarcal::odometry
