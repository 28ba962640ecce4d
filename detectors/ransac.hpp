// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// PCL's RANSAC (pcl::RandomSampleConsensus, fixed seed) for the two models the scan detector
// fits, run as pcl::SACSegmentation runs it (same model, seeds, settings and calls) but without
// linking pcl_segmentation: loading that library (and pcl_features, pcl_filters behind it) cost
// every lidarcal command about 70 ms of start-up, a sixth of `detect` on 1000 scans.

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>
#include <Eigen/Core>

namespace lidarcal::detectors {

struct RansacSettings {
  double threshold_m = 0.0;  ///< inlier distance
  int max_iterations = 0;
  double probability = 0.99;
};

/// A 2D circle (pcl::SACMODEL_CIRCLE2D: centre x, y and radius, radius within [radius_min,
/// radius_max]). False when RANSAC found no model; otherwise its inliers and coefficients.
bool ransacCircle2D(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
                    const RansacSettings& settings, double radius_min_m, double radius_max_m,
                    pcl::Indices& inliers, Eigen::VectorXf& coefficients);

/// A line (pcl::SACMODEL_LINE: a point and a direction).
bool ransacLine(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
                const RansacSettings& settings, pcl::Indices& inliers,
                Eigen::VectorXf& coefficients);

}  // namespace lidarcal::detectors
