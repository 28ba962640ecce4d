// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Landmark-level simulator of Alhashimi et al. 2021 section 4.1: the robot stops along a line (eqs.
// 7-8), each landmark is seen at bearing theta + v (eq. 5) and range f(d) + sigma(d) e (eq. 3).
// Optionally the beams of the lidar's angular grid that fall on each landmark are ray-cast too, so
// the joint refinement can use individual readings (no scans, no detector: fast).

#include <cstdint>
#include <vector>

#include "common/landmark_observations.hpp"
#include "common/scene.hpp"
#include "common/truth.hpp"

namespace lidarcal::simulation {

struct LandmarkLevelConfig {
  std::vector<Cylinder> landmarks;  ///< world positions and radii (ids 1..L)
  PathSpec path;                    ///< stops, scans per stop, sigma_s, sigma_psi
  RangeModel model;                 ///< f, noise law and the sensor's reporting window
  double sigma_theta_rad = 0.0;     ///< noise of each measured centre bearing (eq. 5), per scan
  bool beams = false;               ///< also ray-cast the beam grid on each landmark
  double angle_increment_rad = 0.017453292519943295;  ///< beam grid step (1 degree)
  bool publish_radius = true;  ///< set LandmarkObservations::landmark_radius_m
  /// effects beyond the seeds' model (common/range_effects.hpp); off by default
  RangeEffects effects;
  double mount_yaw_rad = 0.0;  ///< lidar zero angle rotated against the robot (beams only), radians
  /// background behind the landmarks, for mixed pixels only (no occlusion)
  std::vector<Segment> walls;
  /// beam j of the grid points at angle_min_rad + j * angle_increment_rad
  double angle_min_rad = 0.0;
  /// When non-empty: these stops (commanded and actual poses, scans) instead of planStops(path);
  /// parametric bootstrap of measured data (the same geometry as fitted).
  std::vector<TruthStop> stops;
};

struct LandmarkLevelSample {
  LandmarkObservations obs;                       ///< what calibration sees
  std::vector<TruthStop> stops;                   ///< commanded and actual poses
  std::vector<std::vector<double>> true_range_m;  ///< per sighting, per beam: the true distance
};

/// One draw. Randomness: stream 0 for the poses, stream 1 + scan for each scan, effectRng()
/// for the effects. Landmark offsets are Cylinder::range_offset_m; heading errors and odometry
/// scale errors come with the path (sigma_psi_rad, step_error_fraction).
LandmarkLevelSample simulateLandmarkLevel(const LandmarkLevelConfig& config, std::uint64_t seed);

}  // namespace lidarcal::simulation
