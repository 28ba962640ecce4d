// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Straight lines (walls, box faces) in the scan plane: PCL's RANSAC (SACMODEL_LINE) for the
// consensus set, then a total-least-squares line through it in double precision.
// Deterministic like circle_fit.hpp: a fresh pcl::SACSegmentation(random = false) per call.

#include <string>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>
#include <Eigen/Core>

#include "detectors/circle_fit.hpp"

namespace lidarcal::detectors {

struct LineFitConfig {
  /// distance from the line within which a point is an inlier, metres. Default 0.01
  double inlier_threshold_m = 0.01;
  /// run RANSAC from this many points on; below, all points are used. Default 4
  int ransac_min_points = 4;
  int max_iterations = 200;   ///< RANSAC iterations. Default 200
  double probability = 0.99;  ///< RANSAC success probability. Default 0.99

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// A line through `point` along the unit vector `direction`, with its residual.
struct Line2 {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();  ///< a point on the line (the centroid), metres
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();  ///< unit direction
  Eigen::Vector2d normal = Eigen::Vector2d::UnitY();  ///< unit normal (the scatter's smallest axis)
  double rms_m = 0.0;  ///< RMS perpendicular distance of the points, metres
};

struct LineFit {
  FitStatus status = FitStatus::too_few_points;  ///< ok, or why there is no line
  std::string message;                           ///< what went wrong, for a user
  Line2 line;                                    ///< total-least-squares line through the inliers
  pcl::Indices inliers;      ///< indices (into the input cloud) within the threshold
  bool used_ransac = false;  ///< RANSAC chose the inliers
};

/// Fits a line to the points `indices` of `cloud` (x, y only; NaN points skipped).
LineFit fitLine(const pcl::PointCloud<pcl::PointXYZI>& cloud, const pcl::Indices& indices,
                const LineFitConfig& config);

/// Total-least-squares line of at least 2 points (principal axis of the scatter).
Line2 totalLeastSquaresLine(const std::vector<Eigen::Vector2d>& points);

/// The line in normal form, x cos(normal_rad) + y sin(normal_rad) = distance_m with distance_m >=
/// 0: the normal's direction from the origin (the sensor) towards the line, radians, and the line's
/// perpendicular distance from it, metres.
struct NormalForm {
  double normal_rad = 0.0;  ///< direction of the normal from the origin, radians
  double distance_m = 0.0;  ///< perpendicular distance from the origin, metres (>= 0)
};
NormalForm normalForm(const Line2& line);

}  // namespace lidarcal::detectors
