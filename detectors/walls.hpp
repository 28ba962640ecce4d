#pragma once
// Flat surfaces (walls) in one 2D scan, for measurements against a wall: each cluster of the
// segmentation (segmentation.hpp) that a straight line explains (line_fit.hpp) is a wall, with
// its perpendicular distance and normal direction from the sensor.

#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>

#include "detectors/line_fit.hpp"
#include "detectors/segmentation.hpp"

namespace lidarcal::detectors {

struct WallConfig {
  SegmentationConfig segmentation;  ///< clustering in scan order
  LineFitConfig line;               ///< the line fit of each cluster (inlier threshold 0.01 m by default)
  int min_points = 8;               ///< a wall needs this many returns. Default 8
  double min_inlier_fraction = 0.8;  ///< line inliers / cluster returns. Default 0.8
  double min_length_m = 0.2;        ///< extent of the inliers along the line, metres. Default 0.2
  void validate() const;            ///< throws std::invalid_argument naming the first bad field
};

/// One wall in a scan (sensor frame).
struct Wall {
  double normal_rad = 0.0;   ///< direction from the sensor to the nearest point of the line, radians
  double distance_m = 0.0;   ///< perpendicular distance from the sensor to the line, metres
  double rms_m = 0.0;        ///< RMS distance of the inliers to the line, metres
  pcl::Indices inliers;      ///< points on the line, ascending
};

/// Every wall of a scan (sensor at the origin).
std::vector<Wall> findWalls(const pcl::PointCloud<pcl::PointXYZI>& cloud, const WallConfig& config);

}  // namespace lidarcal::detectors
