// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What a sequence's readings and odometry know of each stop's pose: a reading's gradient by its
// pose, the poses' information and marginal covariances under the motion prior (a Laplace
// approximation with the landmarks and the range model held at the fit), and the odometry steps
// as the refinement weighs them. Internal to the diagnosis library.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "diagnosis/pose_gaussians.hpp"
#include "diagnosis/sequence/refits.hpp"

namespace lidarcal::diagnosis::sequence {

/// Distance along a ray to a circle and its derivatives (see rayCircleDistance); the square
/// root is kept away from 0 near the tangent like the incidence (clampCosIncidence).
struct RayGradient {
  double d = 0.0;    ///< distance along the ray, metres
  double dcx = 0.0;  ///< its derivative by the centre's x (unitless)
  double dcy = 0.0;  ///< by the centre's y
  double dr = 0.0;   ///< by the radius
  double da = 0.0;   ///< by the ray's angle, metres per radian
};

RayGradient rayGradient(double px, double py, double a, double cx, double cy, double r);

/// Derivative of a reading's expected value with respect to its stop's pose (x, y, heading):
/// the distance along the ray moves against the pose as it moves with the landmark's centre.
Eigen::Vector3d poseGradient(const JointResult& fit, const JointReading& r);

/// Mean and variance of the distance along a held-out beam to its pole when the scan's pose is
/// uncertain (Gaussian about the fit, covariance `cov`): the ray's closest approach `along` and
/// miss distance `perp` are linear in the pose, and poleDistanceMoments conditions on the hit
/// (linearised alone, a thin pole's outermost beams get many times their variance:
/// docs/results/hidden-effects.md). root_extra: poleDistanceMoments's, for a fit with an incidence
/// bias.
DistanceMoments heldOutDistance(const JointResult& fit, const JointReading& r,
                                const Eigen::Matrix3d& cov, double root_extra = 0.0);

/// A reading's information on its stop's pose: its pose gradient g and its standard deviation.
struct PoseInformation {
  std::size_t stop = 0;  ///< the reading's stop
  /// its expected value's gradient by the pose (x, y, heading)
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  double sigma = 0.0;  ///< its standard deviation, metres
};

/// The readings of `obs` under `fit`, as information on their stops' poses (computed once for
/// poseCovariances and noiseDofFactor).
std::vector<PoseInformation> poseInformation(const LandmarkObservations& obs,
                                             const JointResult& fit, const JointConfig& cfg);

/// The odometry from stop a to stop b > a of a fit under the motion prior, as the refinement
/// weighs it (MotionPriorCost): its residual (the commanded step against the fitted one in the
/// frame of stop a, its translation divided by 1 + s; heading change) in units of its standard
/// deviations, the residual's derivatives by the two poses, and ln(1 / (sd_x sd_y sd_psi)).
/// Over a run of steps (b > a + 1) their variances add up (the turns between them neglected).
struct OdometryStep {
  Eigen::Vector3d r = Eigen::Vector3d::Zero();  ///< residual (x, y, heading) in standard deviations
  Eigen::Matrix3d ja = Eigen::Matrix3d::Zero();  ///< its derivatives by pose a
  Eigen::Matrix3d jb = Eigen::Matrix3d::Zero();  ///< its derivatives by pose b
  double inv_t = 0.0;                            ///< 1 / the translation's standard deviation, 1/m
  double log_scale = 0.0;                        ///< ln(1 / (sd_x sd_y sd_psi))
};

OdometryStep odometryStep(const LandmarkObservations& obs, const JointResult& fit,
                          const JointConfig& cfg, std::size_t a, std::size_t b);

/// Information matrix of the poses of a fit under the motion prior, the landmarks and the range
/// model held at the fit: block-tridiagonal, the readings of each stop (Gaussian information
/// g g^T / sigma^2 per reading) on the diagonal blocks `a`, the odometry steps between
/// consecutive stops (odometryStep) on `a` and the blocks (k, k + 1) `b`. `readings`:
/// poseInformation(obs, fit, cfg); `noise_scale`: a factor on every reading's variance.
struct PoseChain {
  std::vector<Eigen::Matrix3d> a;  ///< diagonal blocks
  std::vector<Eigen::Matrix3d> b;  ///< blocks (k, k + 1)
};
PoseChain poseChainInformation(const std::vector<PoseInformation>& readings,
                               const LandmarkObservations& obs, const JointResult& fit,
                               const JointConfig& cfg, double noise_scale);

/// Marginal covariance of every stop's pose in a fit under the motion prior (a Laplace
/// approximation with the landmarks and the range model held at the fit): the inverse of
/// poseChainInformation's matrix (blockTridiagonalInverseDiagonal). `upper`, when given, gets the
/// covariances of neighbouring poses.
std::vector<Eigen::Matrix3d> poseCovariances(const std::vector<PoseInformation>& readings,
                                             const LandmarkObservations& obs,
                                             const JointResult& fit, const JointConfig& cfg,
                                             double noise_scale,
                                             std::vector<Eigen::Matrix3d>* upper = nullptr);

/// Factor that takes a fit's noise variance under the motion prior to the readings' own: with a
/// pose per scan fitted to a dozen readings the residuals are smaller than the noise (the
/// Neyman-Scott problem). The poses take up h = sum of g^T C g / sigma^2 over the readings (their
/// leverages, C the pose's marginal covariance), and the factor is n / (n - h), as a residual
/// variance is divided by its degrees of freedom (docs/results/hidden-effects.md, Robots that never
/// stop).
double noiseDofFactor(const std::vector<PoseInformation>& readings,
                      const std::vector<Eigen::Matrix3d>& cov);

/// What the readings of `obs` and the odometry know of each pose of a fit under the motion prior:
/// the readings' pose information, the factor that takes the fit's noise variance to the
/// readings' own (noiseDofFactor), and the poses' covariances at that variance (`upper`, when
/// given: the neighbours' covariances too).
struct PoseUncertainty {
  std::vector<PoseInformation> info;  ///< the readings' information (poseInformation)
  double dof = 1.0;  ///< noiseDofFactor: the fit's noise variance to the readings' own
  std::vector<Eigen::Matrix3d> cov;  ///< each pose's marginal covariance at that variance
};

PoseUncertainty poseUncertainty(const LandmarkObservations& obs, const JointResult& fit,
                                const JointConfig& cfg,
                                std::vector<Eigen::Matrix3d>* upper = nullptr);

/// Readings a pose needs before the odometry steps at it are held out (a pose is three numbers).
constexpr int kLocatingReadings = 3;

/// Calls fn(k, step, S) for each odometry step k - 1 -> k of a fit under the motion prior whose
/// two poses the readings both locate (kLocatingReadings each): the step (odometryStep) and its
/// leverage S = J C J^T, J its derivatives by the two poses, C their joint covariance
/// (poseUncertainty).
template <typename Fn>
void forEachLocatedStep(const LandmarkObservations& obs, const JointResult& fit,
                        const JointConfig& cfg, Fn fn) {
  const std::size_t n = std::min(fit.poses.size(), obs.commanded.size());
  if (n < 2) return;
  std::vector<Eigen::Matrix3d> upper;
  const PoseUncertainty u = poseUncertainty(obs, fit, cfg, &upper);
  std::vector<int> readings(n, 0);
  for (const auto& r : u.info)
    if (r.stop < n) ++readings[r.stop];
  for (std::size_t k = 1; k < n; ++k) {
    if (readings[k - 1] < kLocatingReadings || readings[k] < kLocatingReadings) continue;
    const OdometryStep o = odometryStep(obs, fit, cfg, k - 1, k);
    Eigen::Matrix<double, 6, 6> joint;
    joint << u.cov[k - 1], upper[k - 1], upper[k - 1].transpose(), u.cov[k];
    Eigen::Matrix<double, 3, 6> j;
    j << o.ja, o.jb;
    fn(k, o, Eigen::Matrix3d(j * joint * j.transpose()));
  }
}

}  // namespace lidarcal::diagnosis::sequence
