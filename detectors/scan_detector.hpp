// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Landmark candidates in one 2D scan: segment (segmentation.hpp), then classify each cluster as a
// circle (a pole: landmark candidate), a line (wall, box face) or clutter.
//
// A cluster is a circle when (Alhashimi et al. 2021 section 2, A1: cylinders of known or
// inferable radius)
//  - it is near enough for its shape to show (t(range) <= max_threshold_to_radius R);
//  - it stands in front of its surroundings: the beams next to its ends have no return or a
//    farther one (require_free_edges; a wall seen between chair legs is cut by nearer returns);
//  - it has enough points and its width across the line of sight fits the landmark: at most
//    2 R extent_factor, and an angular width of at least min_width_fraction of the angle a pole
//    of radius R subtends at that range (less two beam steps);
//  - the circle fit (circle_fit.hpp; centre with R fixed when R is known) keeps min_inlier_fraction
//    of the points, its RMS is below max_rms_fraction t, its centre lies behind the arc, and the
//    free-radius fit, when it is well determined, agrees with R;
//  - a straight line does not explain the points clearly better (line_evidence, line_rms_ratio).
// t(r) = threshold_m + threshold_per_m2 r^2 is the inlier threshold at range r: about three
// standard deviations of a triangulation lidar whose noise grows with the square of the range
// (Alhashimi et al. 2016 eq. 1).

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <pcl/types.h>

#include "detectors/circle_fit.hpp"
#include "detectors/segmentation.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::detectors {

/// A landmark expected in a scan, with its radius (sensor frame).
struct RadiusHint {
  double x_m = 0.0;       ///< expected centre x (sensor frame), metres
  double y_m = 0.0;       ///< expected centre y (sensor frame), metres
  double radius_m = 0.1;  ///< the landmark's radius, metres
};

struct DetectionConfig {
  SegmentationConfig segmentation;  ///< clustering in scan order
  /// Known landmark radius, metres (sequence.json `landmark_radius_m`). Unset: free fits within
  /// [radius_min_m, radius_max_m], radius estimated later over all observations. Default unset.
  std::optional<double> landmark_radius_m;
  /// smallest landmark radius when unknown, metres (55 mm poles: 0.0275). Default 0.02
  double radius_min_m = 0.02;
  double radius_max_m = 0.30;  ///< largest landmark radius when unknown, metres. Default 0.30
  /// free fit must be >= factor R when R is known. Default 0.5
  double known_radius_min_factor = 0.5;
  /// free fit must be <= factor R when R is known. Default 2.0
  double known_radius_max_factor = 2.0;
  int min_points = 3;         ///< returns a cluster needs with R known. Default 3
  int min_points_free = 4;    ///< returns a cluster needs with R unknown. Default 4
  double threshold_m = 0.01;  ///< inlier threshold at range 0, metres. Default 0.01
  /// growth of the threshold with range squared, 1/m. Default 0.005
  double threshold_per_m2 = 0.005;
  /// Clusters so far that t exceeds this many radii (the largest radius when unknown) are not
  /// judged: the noise hides the shape. Default 2.
  double max_threshold_to_radius = 2.0;
  double max_rms_fraction = 0.6;     ///< fit RMS must be <= fraction * threshold. Default 0.6
  double min_inlier_fraction = 0.7;  ///< circle inliers / cluster returns. Default 0.7
  /// width across the line of sight <= 2 R factor (range bias stretches arcs). Default 1.3
  double extent_factor = 1.3;
  /// angular width >= fraction of the pole's angle at that range. Default 0.6
  double min_width_fraction = 0.6;
  /// flat if a line lowers the sum of squares by this many noise variances... Default 9
  double line_evidence = 9.0;
  /// ...and its RMS per degree of freedom is below ratio * the circle's. Default 1
  double line_rms_ratio = 1.0;
  /// refuse clusters whose neighbouring beams are nearer. Default true
  bool require_free_edges = true;
  /// Without a known radius, the free radius must be determined to this fraction (its standard
  /// deviation, noise taken as max(fit RMS, t / 3)): a noisy box corner is no pole. Default 0.25.
  double max_radius_uncertainty = 0.25;
  int free_radius_check_points = 6;  ///< check the free radius from this many inliers on. Default 6
  int max_iterations = 1000;         ///< RANSAC iterations (circle and line). Default 1000
  /// Landmarks expected in this scan: a cluster whose mean lies within hint_distance_m of one
  /// hint's circle is fitted with that radius fixed (when landmark_radius_m is unset). Filled by
  /// detectSequence's second pass once radii are estimated. Default empty.
  std::vector<RadiusHint> radius_hints;
  double hint_distance_m = 0.35;  ///< see radius_hints, metres. Default 0.35
  int ransac_min_points = 6;      ///< RANSAC from this many points on. Default 6

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
  /// Inlier threshold t(r) at range r, metres.
  double threshold(double range_m) const {
    return threshold_m + threshold_per_m2 * range_m * range_m;
  }
};

/// What a cluster was classified as.
enum class ClusterKind { circle, line, clutter };
const char* toString(ClusterKind kind);

/// One cluster of a scan, after classification (no indices kept: scans can be long).
struct ClusterSummary {
  int first_index = 0;  ///< first point (beam) of the cluster in scan order
  /// last point (beam); smaller than first_index when closed across the scan's end
  int last_index = 0;
  std::size_t points = 0;                   ///< returns in the cluster
  ClusterKind kind = ClusterKind::clutter;  ///< classification
  std::string reason;                       ///< why it is not a circle (empty for circles)
};

/// A circular landmark candidate in one scan. Positions in the sensor frame.
struct Detection {
  /// centre x (sensor frame), metres; fitted with radius_m fixed when radius_fixed
  double centre_x_m = 0.0;
  double centre_y_m = 0.0;  ///< centre y (sensor frame), metres
  /// radius of the reported circle, metres (known, estimated, or the free fit)
  double radius_m = 0.0;
  bool radius_fixed = false;  ///< the centre was fitted with the radius fixed
  double bearing_rad = 0.0;   ///< atan2(centre_y, centre_x), radians, (-pi, pi]
  double range_m = 0.0;       ///< distance from the sensor to the centre, metres
  double rms_m = 0.0;         ///< RMS distance of the inliers to the reported circle, metres
  FitStatus free_status = FitStatus::too_few_points;  ///< status of the free-radius fit
  /// free-radius fit: centre x, metres (valid when free_status is ok)
  double free_centre_x_m = 0.0;
  double free_centre_y_m = 0.0;       ///< free-radius fit: centre y, metres
  double free_radius_m = 0.0;         ///< free-radius fit: radius, metres
  double free_rms_m = 0.0;            ///< free-radius fit: RMS, metres
  double free_radius_stddev_m = 0.0;  ///< free-radius fit: standard deviation of the radius, metres
  std::size_t cluster_points = 0;     ///< returns in the cluster
  /// Points of the scan on the circle, in beam order along the arc: a pole across the scan's end
  /// runs from the last beams on to the first ones, so front() and back() are its edges.
  pcl::Indices inliers;
  /// The inliers' x, y (sensor frame, as read) and intensity, in the order of `inliers`; filled
  /// only where a sequence keeps its scans' detections (sequence_detector.hpp), so that the
  /// sightings need no second read of the scans.
  std::vector<std::array<float, 3>> inlier_xyi;
};

/// Everything found in one scan.
struct ScanDetections {
  /// position of the scan in its sequence (set by the caller; orders landmark ids)
  std::size_t scan_index = 0;
  /// stop of the scan (set by the caller; association counts distinct stops)
  std::size_t stop = 0;
  std::size_t returns = 0;               ///< points with a return
  std::vector<Detection> detections;     ///< accepted circles
  std::vector<ClusterSummary> clusters;  ///< every cluster with its classification
};

/// Finds circular landmark candidates in a scan (sensor at the origin of the cloud).
ScanDetections detectScan(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                          const DetectionConfig& config);
/// The same for a scan read from a sequence.
ScanDetections detectScan(const io::Scan& scan, const DetectionConfig& config);

/// Sets a detection's centre, bearing and range from a circle (sensor frame).
void setCentre(Detection& d, const Circle2& circle);

}  // namespace lidarcal::detectors
