// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Flat surfaces (walls) in one 2D scan, for measurements against a wall: each cluster of the
// segmentation (segmentation.hpp) is split into straight pieces (split and merge: a piece that
// a line does not explain is cut at the point farthest from the chord between its ends, as in
// Douglas-Peucker), each piece a line explains (line_fit.hpp) is a wall, pieces on one line (a
// wall interrupted by a table leg, or split at a noisy point) are merged into one wall, and a
// return that two walls claim (near a corner) is given to neither; each wall with its
// perpendicular distance and normal direction from the sensor.
// For points already ordered into runs (beam means of a static recording:
// diagnosis/static_scene/walls.cpp), findWallsInRun splits the runs into straight pieces instead.

#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>
#include <Eigen/Core>

#include "detectors/line_fit.hpp"
#include "detectors/segmentation.hpp"

namespace lidarcal::detectors {

struct WallConfig {
  SegmentationConfig segmentation;  ///< clustering in scan order
  /// The line fit of each piece. Its inlier threshold is the threshold at range 0: a piece at
  /// mean range r uses line.inlier_threshold_m + threshold_per_m2 * r^2 (the detection's
  /// t(r) = A + B r^2). Default 0.01 m.
  LineFitConfig line;
  /// Growth of the inlier threshold with the range squared, 1/m (a triangulation lidar's noise
  /// grows with range squared). Default 0: the threshold is line.inlier_threshold_m everywhere.
  double threshold_per_m2 = 0.0;
  int min_points = 8;                ///< a wall needs this many returns. Default 8
  double min_inlier_fraction = 0.8;  ///< line inliers / piece returns. Default 0.8
  double min_length_m = 0.2;         ///< extent of the inliers along the line, metres. Default 0.2
  /// Two walls whose normals differ by less than this, radians, and whose distances differ by
  /// less than their inlier threshold are one wall (merged). Default 0.035 (2 degrees).
  double merge_angle_rad = 0.035;
  void validate() const;  ///< throws std::invalid_argument naming the first bad field
};

/// One wall in a scan (sensor frame).
struct Wall {
  double normal_rad = 0.0;  ///< direction from the sensor to the nearest point of the line, radians
  double distance_m = 0.0;  ///< perpendicular distance from the sensor to the line, metres
  double rms_m = 0.0;       ///< RMS distance of the inliers to the line, metres
  pcl::Indices inliers;     ///< points on the line, ascending
};

/// Every wall of a scan (sensor at the origin), by ascending normal direction.
std::vector<Wall> findWalls(const pcl::PointCloud<pcl::PointXYZI>& cloud, const WallConfig& config);

/// The same finder for points that are already in order and free of jumps (a run: e.g. the mean
/// readings of neighbouring beams over many scans, which need no segmentation and no consensus):
/// each run is split recursively at its point farthest from the total-least-squares line until
/// every piece is straight.
struct RunWallConfig {
  /// a piece is straight when no point lies farther from its line, metres. Default 0.025
  double max_deviation_m = 0.025;
  int min_points = 8;  ///< pieces with fewer points are dropped. Default 8
  /// a run's first and last point (of 3 or more) border a gap or a jump: left out. Default true
  bool drop_run_ends = true;
  void validate() const;  ///< throws std::invalid_argument naming the first bad field
};

/// The straight pieces of one run of ordered points (sensor at the origin), in the order the
/// splitting finds them: each a Wall whose inliers index `run`, ascending and contiguous.
std::vector<Wall> findWallsInRun(const std::vector<Eigen::Vector2d>& run,
                                 const RunWallConfig& config);

}  // namespace lidarcal::detectors
