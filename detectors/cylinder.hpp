// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Cylinders in 3D clouds (multi-beam lidars, depth cameras): the pipeline of PCL's cylinder
// segmentation tutorial. Pass-through on z, normals from the k nearest neighbours, the dominant
// plane removed (SACMODEL_NORMAL_PLANE), then SACSegmentationFromNormals with SACMODEL_CYLINDER.
// Deterministic: PCL's sample-consensus objects are built with random = false (fixed seed).

#include <string>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>
#include <Eigen/Core>

#include "detectors/circle_fit.hpp"

namespace lidarcal::detectors {

struct CylinderConfig {
  /// pass-through: keep points with z in [z_min_m, z_max_m], metres. Default 0
  double z_min_m = 0.0;
  double z_max_m = 1.5;        ///< Default 1.5
  int normal_neighbours = 50;  ///< k nearest neighbours per normal. Default 50
  bool remove_plane = true;    ///< remove the dominant plane first (table, floor). Default true
  /// weight of the normal angle in the plane distance. Default 0.1
  double plane_normal_weight = 0.1;
  double plane_threshold_m = 0.03;  ///< plane inlier distance, metres. Default 0.03
  int plane_iterations = 100;       ///< plane RANSAC iterations. Default 100
  double normal_weight = 0.1;  ///< weight of the normal angle in the cylinder distance. Default 0.1
  double threshold_m = 0.05;   ///< cylinder inlier distance, metres. Default 0.05
  int iterations = 10000;      ///< cylinder RANSAC iterations. Default 10000
  double radius_min_m = 0.0;   ///< smallest radius, metres (finite). Default 0
  double radius_max_m = 0.1;   ///< largest radius, metres (finite). Default 0.1

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

struct CylinderResult {
  FitStatus status = FitStatus::too_few_points;             ///< ok, or why there is no cylinder
  std::string message;                                      ///< what went wrong, for a user
  Eigen::Vector3d point_on_axis = Eigen::Vector3d::Zero();  ///< a point of the axis, metres
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit axis direction (sign arbitrary)
  double radius_m = 0.0;                            ///< radius, metres
  pcl::Indices inliers;  ///< cylinder points, indices into the input cloud
  /// removed plane (a, b, c, d), when remove_plane
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();
  std::size_t plane_inliers = 0;  ///< points of the removed plane
  std::size_t points_used = 0;    ///< points after the pass-through filter
};

/// Finds the dominant cylinder of a 3D cloud.
CylinderResult detectCylinder(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
                              const CylinderConfig& config);

}  // namespace lidarcal::detectors
