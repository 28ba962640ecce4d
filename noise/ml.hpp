// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Maximum-likelihood noise estimation beside Sharma 2020: variance-component estimation (VCE) in
// the batch least-squares adjustment of poses, landmarks and sensor biases.
//
// Model (linearised at the solution): observations z = h(pose_k, landmark_j) + bias_s + e with
// e ~ N(0, diag(var_range_s, var_bearing_s)); commanded motions u_k = (pose_{k-1} (-) pose_k) + w
// with w ~ N(0, diag(q_dx, q_dy, q_dtheta)). Each of the 2S + 3 variances is a variance component.
// Iteration (Foerstner 1979, iterated Helmert VCE; at its fixed point the restricted maximum
// likelihood estimate of the linearised model):
//   1. solve the weighted least squares with the current variances (Ceres);
//   2. per group g: Omega_g = sum of its squared residuals, r_g = n_g - tr(W_g A_g N^-1 A_g^T)
//      (its redundancy: observations minus their share of the unknowns);
//   3. var_g <- Omega_g / r_g (Foerstner), taken as a scoring step of the REML likelihood
//      (lengthened by up to r_g / sum r_ii^2, which speeds up components near zero, and damped
//      when the step changes sign); repeat until no variance changes by more than `tolerance`
//      of itself or of its standard error.
// The standard error of var_g is var_g sqrt(2 / sum r_ii^2) (~ var_g sqrt(2 / r_g) when the
// redundancy numbers are near 1).
//
// Gauge and identifiability: pose 0 is the frame (fixed at the origin). Differences of biases
// between sensors are fixed by the landmarks they share. The biases common to all sensors are
// referenced to the odometry: a common range bias by the commanded translation lengths, a
// common bearing bias by the commanded direction of travel in the robot frame; with no
// translation they are not identifiable (DataError).

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/observation.hpp"
#include "common/pose2.hpp"
#include "noise/problem.hpp"

namespace lidarcal::noise {

struct MlNoiseConfig {
  int max_iterations = 100;  ///< VCE iterations (adjustments) at most
  /// stop when every variance changes by less than this fraction (of itself or its standard error)
  double tolerance = 1e-3;
  /// floor of every variance (a component at the floor is reported as such), unit^2
  double min_variance = 1e-8;
  bool estimate_biases = true;  ///< estimate each sensor's range and bearing bias (else fixed at 0)
  /// estimate the process variances (else fixed at `initial.process`)
  bool estimate_process = true;
  /// starting variances; empty sensors: 1 for the sensors, 0.01 for the process
  NoiseSetting initial;
  int solver_iterations = 50;  ///< Ceres iterations per adjustment at most
  /// Standard errors from the full information of the variances up to this many motions (K - 1);
  /// beyond, the diagonal estimate. Cost: 3(K-1) solves and a 3(K-1)^2 matrix (72 MB at 1000).
  int max_motions_for_information = 1000;
  void validate() const;  ///< throws InputError
};

/// The unknowns of the adjustment.
struct MlState {
  std::vector<Pose2> poses;                      ///< K poses; poses[0] is the origin (the gauge)
  std::vector<std::array<double, 2>> landmarks;  ///< L positions (x, y), metres, frame of pose 0
  std::vector<std::array<double, 2>> biases;     ///< S biases (range m, bearing rad)
};

/// One variance component.
struct MlGroup {
  /// "s0.range", "s0.bearing", ..., "process.dx", "process.dy", "process.dtheta"
  std::string name;
  std::size_t count = 0;    ///< observations in the group
  double redundancy = 0.0;  ///< r_g (sum of the group's redundancy numbers)
  double sum_sq = 0.0;      ///< Omega_g, sum of squared (unweighted) residuals, unit^2
  double variance = 0.0;    ///< estimate, unit^2
  /// of the variance, unit^2 (MlNoiseResult::standard_error_method says how)
  double standard_error = 0.0;
  bool at_floor = false;  ///< the estimate reached min_variance (true value ~0 or not identifiable)
};

struct MlNoiseResult {
  bool converged = false;  ///< variances stopped changing within max_iterations
  std::string message;     ///< why not converged, or notes (empty when all is well)
  NoiseSetting noise;      ///< estimated biases (means) and variances
  std::vector<double> bias_standard_error;  ///< per sensor: range (m), bearing (rad), interleaved
  std::vector<MlGroup> groups;              ///< 2S + 3 variance components
  /// "information": from the inverse REML information of the estimated variances (terms with a
  /// process group in full); "diagonal": var sqrt(2 / sum r_ii^2) per group, which ignores the
  /// correlation of the motion residuals along the chain and overstates the process errors
  /// (used beyond max_motions_for_information, for fixed variances and those at the floor).
  std::string standard_error_method = "diagonal";
  MlState state;  ///< adjusted poses, landmarks, biases
  /// restricted -log likelihood (nats, constants dropped) at each iteration's variances
  std::vector<double> objective_trace;
  /// variances (order of `groups`) after each iteration
  std::vector<std::vector<double>> variance_trace;
  int iterations = 0;         ///< adjustments solved (VCE iterations)
  int solver_iterations = 0;  ///< Ceres iterations over all adjustments
};

/// Estimates the noise. Throws DataError when the data cannot support it (no translation in
/// the odometry while biases are estimated, a group without redundancy).
MlNoiseResult estimateNoiseMl(const NoiseProblem& problem, const MlNoiseConfig& config);

/// Dead reckoning from pose 0 and landmarks averaged from their inverse observations: the
/// starting point of the adjustment.
MlState initialState(const NoiseProblem& problem);

/// Unweighted residuals (model minus reading) at `state`, in order: for each observation of
/// the problem its range and wrapped bearing residual, then for k = 1..K-1 the motion residual
/// (dx, dy, wrapped dtheta). Group of each residual in `group` (0..2S+2, as in
/// MlNoiseResult::groups).
std::vector<double> residualsAt(const NoiseProblem& problem, const MlState& state,
                                std::vector<int>* group = nullptr);

/// Redundancy of each group at `state` with variances `variances` (2S + 3 entries, order of
/// MlNoiseResult::groups), using the pose chain's block-tridiagonal structure. With
/// `with_biases` false the biases are constants. Exposed for tests.
std::vector<double> groupRedundancy(const NoiseProblem& problem, const MlState& state,
                                    const std::vector<double>& variances, bool with_biases);

/// REML information matrix of the 2S + 3 variances at `state` (the one behind the standard
/// errors; see standard_error_method). Exposed for tests.
Eigen::MatrixXd groupInformation(const NoiseProblem& problem, const MlState& state,
                                 const std::vector<double>& variances, bool with_biases);

}  // namespace lidarcal::noise
