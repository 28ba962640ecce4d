// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The surfaces behind the walls of a stop: findWalls (walls.hpp) finds the walls of each scan
// anew, and the scans of one stop see the same surfaces, each a little differently (noise, a
// piece found in one scan and not the next). Sightings whose normal directions and distances
// agree are one surface and get one id (WallSighting::wall), as association.hpp gives a pole
// one id over the stops.

#include <vector>

#include <cstddef>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "common/landmark_observations.hpp"
#include "detectors/walls.hpp"

namespace lidarcal::detectors {

struct WallTrackConfig {
  /// Sightings of one surface differ in normal direction by at most this, radians. A short
  /// piece's normal wanders by a few degrees from scan to scan; the distance tells surfaces that
  /// face one way apart. Default 0.175 (10 degrees).
  double max_angle_rad = 0.175;
  /// ... and in distance by at most this, metres (a cabinet 0.4 m in front of its wall is
  /// another surface). Default 0.05.
  double max_distance_m = 0.05;
  void validate() const;  ///< throws std::invalid_argument naming the first bad field
};

/// The walls of one scan (findWalls) as sightings of scan `scan` at stop `stop`, each with the
/// raw readings of its inliers (beam angle from the point, beam index = point index).
std::vector<WallSighting> wallSightings(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                                        std::size_t stop, std::size_t scan,
                                        const WallConfig& config);

/// Sets WallSighting::wall: within each stop, every sighting joins the surface (of those it
/// agrees with, and not yet seen in its scan) whose mean normal and distance are nearest, or
/// starts a new one; longer pieces are placed first. Then surfaces that agree and never share
/// a scan are merged. Ids are 1, 2, ... per stop by ascending mean normal direction. The order
/// of `walls` is kept; the result does not depend on it.
void labelWallSurfaces(std::vector<WallSighting>& walls, const WallTrackConfig& config = {});

}  // namespace lidarcal::detectors
