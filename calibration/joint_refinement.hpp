#pragma once
// Joint refinement (beyond seed 000): one maximum-likelihood problem over every stop's pose,
// the landmark centres, the landmark radius and the bias polynomial, from the individual beam
// readings rather than per-landmark summaries. Each reading y_i of beam angle a_i at stop k on
// landmark l is modelled as
//     y_i = f(d_i) + sigma(d_i) e_i,   d_i = distance along the beam from pose k to circle l,
// with priors tying each pose to its commanded value (sigma_s, sigma_psi; they also fix the
// gauge: translation, rotation and scale of the world). Solved with Ceres (robust Huber loss);
// the noise law is re-estimated from the residuals between solves (iteratively reweighted ML).

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/landmark_observations.hpp"
#include "common/range_model.hpp"

namespace lidarcal::calibration {

struct JointConfig {
  int order = 2;                  ///< bias polynomial order n (>= 1)
  NoiseKind noise = NoiseKind::squared;  ///< noise law re-estimated between solves: squared, polynomial or constant
  int noise_order = 1;            ///< order of the polynomial noise law (seed 000 beta)
  double sigma_s_m = 0.02;        ///< prior std. dev. of each stop coordinate around the commanded one, metres
  double sigma_psi_rad = 0.0087;  ///< prior std. dev. of each stop heading, radians (0.5 degree)
  bool estimate_radius = true;    ///< estimate one common landmark radius (else keep the initial one)
  double huber_sigmas = 2.0;      ///< Huber threshold, in standard deviations of the reading
  double lateral_fraction = 1.0;  ///< use beams passing within this fraction of the radius from the centre
  bool reselect = true;           ///< re-select the beams from the current estimate before every solve
  int outer_iterations = 6;       ///< noise re-estimations at most
  int max_solver_iterations = 200;  ///< Ceres iterations per solve
  bool covariance = true;         ///< compute the covariance of the bias coefficients
  void validate() const;          ///< throws std::invalid_argument
};

/// Starting point (normally the closed-form calibration).
struct JointInit {
  std::vector<Pose2> poses;                ///< one per stop (commanded poses are a fine start)
  std::map<int, Eigen::Vector2d> centres;  ///< landmark id -> centre (world frame)
  double radius_m = 0.1;                   ///< common landmark radius
  RangeModel model;                        ///< bias and noise to start from
};

struct JointResult {
  std::vector<Pose2> poses;                ///< refined stop poses
  std::map<int, Eigen::Vector2d> centres;  ///< refined landmark centres
  std::map<int, Eigen::Matrix2d> centre_covariance;  ///< per landmark, m^2 (when covariance is on)
  double radius_m = 0.0;                   ///< refined common radius
  RangeModel model;                        ///< bias (order n) and noise law
  Eigen::MatrixXd alpha_covariance;        ///< covariance of alpha_0..alpha_n, gauge fixed by the pose priors
  double sigma_theta_rad = 0.0;            ///< RMS of centre-bearing residuals after refinement
  double pose_scatter_m = 0.0;             ///< RMS of refined minus commanded position (per coordinate)
  double heading_scatter_rad = 0.0;        ///< RMS of refined minus commanded heading
  std::size_t readings = 0;                ///< beam readings used
  double residual_rms_m = 0.0;             ///< RMS of reading minus f(predicted distance)
  std::vector<double> distances_m;         ///< predicted distance of every reading used, at the solution
  std::vector<double> readings_m;          ///< the readings themselves (same order)
  std::size_t outliers = 0;                ///< readings beyond the Huber threshold at the end
  double neg_log_likelihood = 0.0;         ///< Gaussian NLL of the readings at the solution
  double aic = 0.0;                        ///< 2 k + 2 NLL, k = bias + noise + radius parameters
  double bic = 0.0;                        ///< k ln N + 2 NLL
  int solver_iterations = 0;               ///< Ceres iterations, all solves
  int outer_iterations = 0;                ///< noise re-estimations done
  bool converged = false;                  ///< last solve converged and the noise settled
  std::string message;                     ///< why not, when not
};

JointResult refineJoint(const LandmarkObservations& obs, const JointInit& init, const JointConfig& config);

/// Distance along a ray from (px, py) at angle a to the circle (cx, cy, r); for a ray that
/// misses, the distance to the point of closest approach (continuous at the tangent).
template <typename T>
T rayCircleDistance(const T& px, const T& py, const T& a, const T& cx, const T& cy, const T& r);

}  // namespace lidarcal::calibration

#include "calibration/joint_refinement_impl.hpp"
