#pragma once
// Flat surfaces (walls) in one 2D scan, for measurements against a wall: each cluster of the
// segmentation (segmentation.hpp) that a straight line explains (line_fit.hpp) is a wall, with
// its perpendicular distance and normal direction from the sensor. For points already ordered
// into runs (beam means of a static recording: diagnosis/static_scene/walls.cpp), the runs are
// split into straight pieces instead (findWallsInRun).

#include <vector>

#include <Eigen/Core>
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

/// The same finder for points that are already in order and free of jumps (a run: e.g. the mean
/// readings of neighbouring beams over many scans, which need no segmentation and no consensus):
/// each run is split recursively at its point farthest from the total-least-squares line until
/// every piece is straight.
struct RunWallConfig {
  double max_deviation_m = 0.025;  ///< a piece is straight when no point lies farther from its line, metres. Default 0.025
  int min_points = 8;              ///< pieces with fewer points are dropped. Default 8
  bool drop_run_ends = true;       ///< a run's first and last point (of 3 or more) border a gap or a jump: left out. Default true
  void validate() const;           ///< throws std::invalid_argument naming the first bad field
};

/// The straight pieces of one run of ordered points (sensor at the origin), in the order the
/// splitting finds them: each a Wall whose inliers index `run`, ascending and contiguous.
std::vector<Wall> findWallsInRun(const std::vector<Eigen::Vector2d>& run, const RunWallConfig& config);

}  // namespace lidarcal::detectors
