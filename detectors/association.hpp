#pragma once
// Association across stops: every detection is moved to the world frame with its scan's
// commanded pose (VIEWPOINT) and detections are linked when closer than link_distance_m
// (single linkage: connected components of a FLANN kd-tree radius graph). A component holding two
// detections of one scan is split by relinking it with a shorter distance. Components seen at
// fewer than min_stops stops (spurious circles, chair legs seen once) are discarded, where a stop
// counts when at least min_scan_fraction of its scans detected the landmark; the rest are the
// landmarks, one id each for the whole sequence.
//
// The result does not depend on the order of the input: the components are a property of the
// set, and ids are assigned by first sighting (smallest ScanDetections::scan_index), then by
// bearing in that scan (counter-clockwise from the sensor's x axis), then by world position.
// No ground truth is used.

#include <cstddef>
#include <string>
#include <vector>

#include "common/pose2.hpp"
#include "detectors/scan_detector.hpp"

namespace lidarcal::detectors {

struct AssociationConfig {
  /// Detections closer than this in the world frame belong to one landmark, metres. Must exceed
  /// the spread of one landmark's detections (range bias changing with distance, odometry error
  /// between consecutive stops) and stay below the distance between landmarks. Default 0.35.
  double link_distance_m = 0.35;
  /// Shortest linking distance tried when splitting a component, metres. Default 0.05.
  double min_link_distance_m = 0.05;
  /// A landmark must be seen at this many distinct stops (capped at the number of stops in the
  /// input). Default 3.
  int min_stops = 3;
  /// A stop counts as seeing a landmark when at least this fraction of its scans detected it: a
  /// pole is found in nearly every scan of a stop, a box corner that looks round only now and
  /// then is not. Default 0.5.
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
  std::size_t stops = 0;       ///< stops that saw it (in at least min_scan_fraction of their scans)
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
  std::size_t discarded_few_stops = 0;         ///< detections in components seen at too few stops
  std::size_t discarded_conflicts = 0;         ///< detections dropped because their scan already had one in the landmark
  std::size_t discarded_components = 0;        ///< components discarded for too few stops
};

/// Groups the detections of all scans into landmarks. viewpoints[i] is the commanded pose of scan i.
Association associate(const std::vector<ScanDetections>& scans, const std::vector<Pose2>& viewpoints,
                      const AssociationConfig& config);

}  // namespace lidarcal::detectors
