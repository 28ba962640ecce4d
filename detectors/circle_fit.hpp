// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Circle fitting in the scan plane: PCL's RANSAC (SACSegmentation + SACMODEL_CIRCLE2D) to find
// the consensus set, then a geometric least-squares refinement in double precision started from
// an algebraic (Taubin) fit. With a known radius the centre is fitted with the radius fixed; the
// free-radius fit is reported beside it.
//
// PCL traps handled here (PCL 1.13):
//  - radius limits are applied only when both bounds differ from their defaults: we always pass
//    two finite bounds (validate() refuses others);
//  - PCL's optimised coefficients may leave the radius limits and then select zero inliers: we do
//    not use PCL's float optimiser; our double refinement falls back to the unoptimised RANSAC
//    model when it leaves the limits or loses inliers;
//  - the default 50 RANSAC iterations are too few: default 1000;
//  - coordinates metres away from the origin lose float precision in the minimal samples: the
//    points are centred (in double) before they are handed to PCL.
// Determinism: every call builds a fresh pcl::SACSegmentation(random = false), whose model and
// sampler seed their own Mersenne twister with PCL's fixed seed 12345 (no std::rand, no global
// state), so a fit depends only on its input points.

#include <optional>
#include <string>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>
#include <Eigen/Core>

namespace lidarcal::detectors {

/// Outcome of a fit.
enum class FitStatus {
  ok,                    ///< a model was found
  too_few_points,        ///< fewer finite points than the model needs
  degenerate,            ///< duplicate or collinear points: no unique model
  no_consensus,          ///< RANSAC found no model within the limits
  radius_out_of_limits,  ///< the best circle's radius is outside [radius_min_m, radius_max_m]
  wrong_side,            ///< the centre lies in front of the arc as seen from `seen_from`
};
const char* toString(FitStatus status);

/// A circle in the plane.
struct Circle2 {
  double x_m = 0.0;       ///< centre x, metres
  double y_m = 0.0;       ///< centre y, metres
  double radius_m = 0.0;  ///< radius, metres
};

struct CircleFitConfig {
  /// Distance from the circle within which a point is an inlier, metres. Default 0.01.
  double inlier_threshold_m = 0.01;
  /// Smallest acceptable radius of the free fit, metres (finite, >= 0). Default 0.
  double radius_min_m = 0.0;
  /// Largest acceptable radius of the free fit, metres (finite). Default 1000.
  double radius_max_m = 1000.0;
  /// Fit the centre with this radius fixed (metres); the free fit is still reported. Default:
  /// unset.
  std::optional<double> fixed_radius_m;
  /// Where the points were seen from (the sensor). When set, a fixed-radius fit starts behind the
  /// arc and a centre in front of the arc is refused (status wrong_side). Default: unset.
  std::optional<Eigen::Vector2d> seen_from;
  /// Run RANSAC only from this many points on; below, all points are inliers. Default 6.
  int ransac_min_points = 6;
  /// RANSAC iterations (PCL's default of 50 is too few for arcs with outliers). Default 1000.
  int max_iterations = 1000;
  /// RANSAC success probability (PCL's stopping rule). Default 0.99.
  double probability = 0.99;
  /// Gauss-Newton/Levenberg-Marquardt iterations of the geometric refinement. Default 50.
  int refine_iterations = 50;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

struct CircleFit {
  FitStatus status = FitStatus::too_few_points;  ///< ok, or why there is no circle
  std::string message;                           ///< what went wrong, for a user
  Circle2 circle;      ///< the reported circle: fixed-radius fit when a radius is given, else free
  double rms_m = 0.0;  ///< RMS distance of the inliers to `circle`, metres
  FitStatus free_status = FitStatus::too_few_points;  ///< status of the free-radius fit
  Circle2 free_circle;      ///< free-radius fit (valid when free_status is ok)
  double free_rms_m = 0.0;  ///< RMS distance of the inliers to `free_circle`, metres
  /// Standard deviation of the free radius per metre of point noise: sqrt((J^T J)^-1) of the
  /// radius at the solution (multiply by the noise level). Infinite when not determined.
  double free_radius_sensitivity = 0.0;
  /// indices (into the input cloud) of the points within the threshold, in the order of `indices`
  pcl::Indices inliers;
  bool used_ransac = false;          ///< RANSAC chose the inliers (false: all points were used)
  bool refinement_rejected = false;  ///< the refined free fit left the limits; RANSAC's model kept
  int iterations = 0;                ///< iterations of the last geometric refinement
};

/// Fits a circle to the points `indices` of `cloud` (x, y only; NaN points skipped).
CircleFit fitCircle(const pcl::PointCloud<pcl::PointXYZ>& cloud, const pcl::Indices& indices,
                    const CircleFitConfig& config);
/// The same for a scan cloud.
CircleFit fitCircle(const pcl::PointCloud<pcl::PointXYZI>& cloud, const pcl::Indices& indices,
                    const CircleFitConfig& config);

// Double-precision building blocks (no PCL), exposed for tests and the radius estimator.

/// Algebraic circle fit of Taubin (1991) via Newton's method on its characteristic polynomial.
/// Returns nothing for fewer than 3 points or (near-)collinear points.
std::optional<Circle2> taubinCircle(const std::vector<Eigen::Vector2d>& points);

/// Result of a geometric least-squares refinement: minimises sum (|p_i - c| - r)^2.
struct GeometricFit {
  Circle2 circle;          ///< refined circle
  double rms_m = 0.0;      ///< RMS of |p_i - c| - r
  int iterations = 0;      ///< iterations used
  bool converged = false;  ///< the step became negligible before the iteration limit
  /// sqrt of the diagonal of (J^T J)^-1 at the solution (x, y, radius; radius 0 when fixed):
  /// standard deviations per metre of point noise. Infinite when the fit is not determined.
  Eigen::Vector3d sensitivity = Eigen::Vector3d::Zero();
};

/// Levenberg-Marquardt on the geometric distances from `start`. With `fixed_radius_m` only the
/// centre moves and the radius stays fixed.
GeometricFit refineCircle(const std::vector<Eigen::Vector2d>& points, const Circle2& start,
                          std::optional<double> fixed_radius_m, int max_iterations = 50);

/// RMS of |p - c| - r over the points.
double circleRms(const std::vector<Eigen::Vector2d>& points, const Circle2& circle);

}  // namespace lidarcal::detectors
