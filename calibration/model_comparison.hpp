// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Two calibrations of one sensor compared where both were fitted: has the bias moved? Each
// model's bias b(d) = f(d) - d is read at distances d_1..d_k inside both fitted ranges, with its
// covariance C = J Sigma_alpha J^T (J_ij = d_i^j); the models come from independent recordings,
// so under no change D = b_a - b_b has covariance C_a + C_b and Wald's statistic
// W = D^T (C_a + C_b)^+ D is chi-square with rank(C_a + C_b) degrees of freedom. The fleet
// report (a sensor calibrated again) and the field watcher's switch (a model learnt on the robot
// against the one in use) both ask this question.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/calibration_model.hpp"

namespace lidarcal::calibration {

/// Whether d lies in the model's fitted range (its reporting window when it records none).
bool insideFittedRange(const CalibrationModel& m, double d_m);

/// Covariance of the bias at the distances, C = J Sigma_alpha J^T, m^2; empty when the model has
/// no usable alpha_covariance.
Eigen::MatrixXd biasCovariance(const CalibrationModel& m, const std::vector<double>& distances_m);

/// A Wald test of D = 0 given its covariance C.
struct WaldTest {
  double statistic = 0.0;  ///< D^T C^+ D
  int dof = 0;             ///< rank of C (eigenvalues above 1e-10 of the largest); 0: no test
  double p = 1.0;          ///< P(chi-square with dof degrees of freedom >= statistic)
};
WaldTest waldTest(const Eigen::VectorXd& D, const Eigen::MatrixXd& C);

/// The two models' difference where both were fitted.
struct ModelDifference {
  bool tested = false;               ///< the test could be made
  std::string why_not;               ///< when not: why (no shared distance, no covariance)
  std::vector<double> distances_m;   ///< the distances compared (those inside both fitted ranges)
  std::vector<double> difference_m;  ///< b_a(d) - b_b(d) at each, metres
  std::vector<double> se_m;          ///< its standard error at each, metres
  WaldTest wald;                     ///< against no change
};

/// Compares model `a` with model `b` at those of `distances_m` inside both fitted ranges.
ModelDifference compareModels(const CalibrationModel& a, const CalibrationModel& b,
                              const std::vector<double>& distances_m);

}  // namespace lidarcal::calibration
