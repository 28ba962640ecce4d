#pragma once
// Association across stops, in world coordinates from each scan's commanded pose (VIEWPOINT):
//  1. at each stop (one pose: detections differ by noise only) the detections closer than
//     stop_link_distance_m form stop clusters, one detection per scan; a cluster is strong when
//     found in at least min_scan_fraction of the stop's scans (a pole is found in nearly every
//     scan, a box corner that looks round now and then is not);
//  2. strong stop clusters closer than link_distance_m are linked across stops (single linkage:
//     connected components of a FLANN kd-tree radius graph), which follows a landmark whose
//     apparent position creeps from stop to stop (range bias changing with distance, odometry
//     drift); a group holding two clusters of one stop is split by relinking it with a shorter
//     distance; groups with fewer than min_stops strong clusters are discarded (chair legs,
//     spurious circles);
//  3. a weak stop cluster joins a landmark whose strong cluster at the nearest stop (by index:
//     stops follow the path) lies within stop_link_distance_m, if that landmark has nothing
//     else at its stop.
// The result does not depend on the order of the input: groups are properties of the set, and
// ids are assigned by first sighting (smallest ScanDetections::scan_index), then by bearing in
// that scan (counter-clockwise from the sensor's x axis), then by world position.
// No ground truth is used.

#include <cstddef>
#include <deque>
#include <string>
#include <tuple>
#include <vector>

#include "common/pose2.hpp"
#include "detectors/scan_detector.hpp"

namespace lidarcal::detectors {

struct AssociationConfig {
  /// Detections closer than this in the world frame belong to one landmark, metres. Must exceed
  /// the spread of one landmark's detections (range bias changing with distance, odometry error
  /// between consecutive stops) and stay below the distance between landmarks. Default 0.35.
  double link_distance_m = 0.35;
  /// Detections of one stop closer than this belong to one object, metres. Default 0.2.
  double stop_link_distance_m = 0.2;
  /// Shortest linking distance tried when splitting a component, metres. Default 0.05.
  double min_link_distance_m = 0.05;
  /// A landmark must be seen (strongly) at this many distinct stops (capped at the number of
  /// stops in the input). Default 3.
  int min_stops = 3;
  /// A stop sees a landmark strongly when at least this fraction of its scans detected it.
  /// Default 0.5.
  double min_scan_fraction = 0.5;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// One landmark over the whole sequence.
struct Landmark {
  int id = 0;                  ///< 1-based id, the `label` of its points
  double x_m = 0.0;            ///< mean world x of its detections (commanded poses), metres
  double y_m = 0.0;            ///< mean world y of its detections, metres
  std::size_t detections = 0;  ///< detections with this id
  std::size_t stops = 0;       ///< stops that saw it strongly (in at least min_scan_fraction of their scans)
  std::size_t first_scan = 0;  ///< smallest scan_index that saw it
  double radius_m = 0.0;       ///< median radius of its detections, metres (detectSequence: known or jointly estimated)
  bool radius_estimated = false;  ///< radius_m was estimated jointly over its observations (landmark_radius.hpp)
};

struct Association {
  std::vector<Landmark> landmarks;             ///< ids 1..L in this order
  /// Landmark id of each detection: ids[i][j] for detection j of input scan i; 0 = not a landmark.
  std::vector<std::vector<int>> ids;
  std::size_t detections = 0;                  ///< detections in the input
  std::size_t assigned = 0;                    ///< detections given an id
  std::size_t discarded_few_stops = 0;         ///< detections in groups seen at too few stops (or weak and alone)
  std::size_t discarded_conflicts = 0;         ///< detections (or stop clusters) dropped as a second one of their scan (stop)
  std::size_t discarded_components = 0;        ///< groups discarded for too few stops
};

/// Groups the detections of all scans into landmarks. viewpoints[i] is the commanded pose of scan i.
/// (Stage 1 per stop with clusterStop, then linkStopClusters.)
Association associate(const std::vector<ScanDetections>& scans, const std::vector<Pose2>& viewpoints,
                      const AssociationConfig& config);

// ---- The same in two steps, for streaming: stage 1 needs the detections of one stop only;
// stages 2-3 need only the stop clusters (about 100 bytes per object per stop). ----

/// Order-free identity of a detection: (scan_index, stop, bearing in [0, 2 pi), world x, world y).
using DetectionKey = std::tuple<std::size_t, std::size_t, double, double, double>;

/// Stage 1 summary: the detections of one object at one stop.
struct StopCluster {
  std::size_t stop = 0;
  bool strong = false;         ///< found in at least min_scan_fraction of the stop's scans
  double x_m = 0.0, y_m = 0.0;  ///< centroid of its detections, world frame, metres
  std::size_t detections = 0;  ///< one per scan at most
  double radius_m = 0.0;       ///< median radius of its detections, metres
  DetectionKey first;          ///< key of its first detection
};

/// The stop clusters of a sequence: a deque, which grows without copying (and without the
/// doubled capacity of a vector: there are several per stop).
using StopClusters = std::deque<StopCluster>;

/// Stage 1 at one stop: `scans` are all the scans of one stop (ScanDetections::stop equal),
/// viewpoints[i] the commanded pose of scans[i]. Appends the stop's clusters to `out` (in an
/// order that depends only on the detections) and, when `cluster_of` is given, sets
/// (*cluster_of)[i][j] to the index in `out` of detection j of scans[i] (-1: dropped as a second
/// detection of its scan). Returns the number of detections dropped that way.
std::size_t clusterStop(const std::vector<const ScanDetections*>& scans, const std::vector<Pose2>& viewpoints,
                        const AssociationConfig& config, StopClusters& out,
                        std::vector<std::vector<int>>* cluster_of = nullptr);

/// Landmark ids of one scan's detections: cluster_of[j] is detection j's cluster (clusterStop),
/// counted from `first` in landmark_of (linkStopClusters), or -1; id 0 for no landmark.
std::vector<int> landmarkIds(const std::vector<int>& cluster_of, const std::vector<int>& landmark_of, std::size_t first = 0);

/// Stages 2-3 over the clusters of every stop: `stops` distinct stops in the input (those without
/// detections included), `stage1_conflicts` the sum of clusterStop's returns. Returns the
/// landmarks (Association::ids left empty) and sets landmark_of[k] to the id of cluster k (0: none).
/// A landmark's radius_m is the median radius of its detections (each cluster's median, weighted
/// by its number of detections).
Association linkStopClusters(const StopClusters& clusters, std::size_t stops, std::size_t stage1_conflicts,
                             const AssociationConfig& config, std::vector<int>& landmark_of);

}  // namespace lidarcal::detectors
