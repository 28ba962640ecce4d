// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The delete-a-group jackknife covariance (Efron and Stein 1981): from G estimates, each made
// without one group (a stop, or a run of stops), (G - 1)/G sum_g (a_-g - mean)(a_-g - mean)^T.
// Used where the readings of one group share an error the per-reading covariance cannot see
// (one tape measurement per stop; the triangulation's error in the closed form).

#include <vector>

#include <Eigen/Core>

namespace lidarcal::calibration {

/// The jackknife covariance of the leave-one-group-out estimates (at least two, of one size).
inline Eigen::MatrixXd jackknifeCovariance(const std::vector<Eigen::VectorXd>& leave_out) {
  const double groups = static_cast<double>(leave_out.size());
  const Eigen::Index p = leave_out.front().size();
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(p);
  for (const auto& a : leave_out) mean += a / groups;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(p, p);
  for (const auto& a : leave_out) cov += (a - mean) * (a - mean).transpose();
  return cov * ((groups - 1.0) / groups);
}

}  // namespace lidarcal::calibration
