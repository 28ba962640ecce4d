// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A simulated world: a 2D scanning lidar on a robot that stops along a straight line (or drives
// along a route without stopping) among vertical cylinders (landmarks, clutter) and wall
// segments. Plain data; io/scene_io reads it from JSON, simulation/ ray-casts it.

#include <cstdint>
#include <string>
#include <vector>

#include "common/pose2.hpp"
#include "common/range_effects.hpp"
#include "common/range_model.hpp"

namespace lidarcal {

/// A vertical cylinder seen as a circle in the scan plane.
struct Cylinder {
  double x_m = 0.0;       ///< centre x in the world frame, metres
  double y_m = 0.0;       ///< centre y in the world frame, metres
  double radius_m = 0.1;  ///< radius, metres (> 0)
  /// added to every reading on this surface (reflectivity, colour), metres
  double range_offset_m = 0.0;
  /// return intensity the sensor reports on this surface (0: none recorded)
  double intensity = 0.0;
};

/// A straight wall segment in the world frame.
struct Segment {
  double x0_m = 0.0, y0_m = 0.0;  ///< first end point, metres
  double x1_m = 1.0, y1_m = 0.0;  ///< second end point, metres
  /// added to every reading on this surface (reflectivity, colour), metres
  double range_offset_m = 0.0;
  /// return intensity the sensor reports on this surface (0: none recorded)
  double intensity = 0.0;
};

/// The scanning lidar: beam layout, range model and angular noise.
struct SensorSpec {
  std::string name = "simulated-lidar";  ///< written to sequence.json
  int beams = 360;                       ///< beams per scan (one 360-degree sweep)
  double angle_min_rad = 0.0;            ///< angle of beam 0 in the sensor frame, radians
  double angle_increment_rad = 0.017453292519943295;  ///< angular step between beams (1 degree)
  RangeModel range;                ///< bias f(d), noise law and range window [min, max]
  double bearing_noise_rad = 0.0;  ///< std. dev. of per-beam angular jitter, radians
  double mount_yaw_rad = 0.0;      ///< lidar zero angle rotated against the robot, radians
  RangeEffects effects;            ///< effects beyond the seeds' model (all off by default)
};

/// How the robot moves through the scene.
enum class PathKind {
  stops,    ///< stop and go along a straight line (Alhashimi et al. 2021 eqs. 7-8); the default
  driving,  ///< never stops: a pose per scan along a smooth route, VIEWPOINT from noisy odometry
};

/// One piece of a driving route: `length_m` of travel over which the heading turns by
/// `turn_rad` at a constant rate (an arc of radius length_m / |turn_rad|; 0: a straight line).
struct RouteSegment {
  double length_m = 1.0;  ///< travel along the piece, metres (> 0). Default 1
  /// heading change over the piece, radians, counter-clockwise positive. Default 0
  double turn_rad = 0.0;
};

/// Odometry of a driving robot: every step between consecutive poses is measured with errors
/// that grow with the motion, and the measured steps are chained into the commanded poses
/// (VIEWPOINT), so their error is a random walk along the route. For a true step of length s
/// turning by dpsi (robot frame), the measured step is
///   along  = s_along / (1 + step_error_fraction) + translation_fraction s e1,
///   across = s_across / (1 + step_error_fraction) + translation_fraction s e2,
///   turn   = dpsi + (heading_rad_per_m s + heading_fraction |dpsi|) e3,   e1..e3 ~ N(0, 1).
struct OdometryNoise {
  /// std. dev. of the measured step along and across the motion per metre of step. Default 0
  double translation_fraction = 0.0;
  /// std. dev. of the measured heading change per metre of step, rad/m. Default 0
  double heading_rad_per_m = 0.0;
  /// std. dev. of the measured heading change per radian turned. Default 0
  double heading_fraction = 0.0;
};

/// A driving robot (PathKind::driving).
struct DrivingSpec {
  /// The route, followed from PathSpec::start piece by piece, from the first piece again after
  /// the last (a closed route loops). Default: one straight metre.
  std::vector<RouteSegment> route{RouteSegment{}};
  double speed_m_per_scan = 0.02;  ///< travel between consecutive poses, metres (> 0). Default 0.02
  OdometryNoise odometry;          ///< how the commanded poses drift from the true ones
};

/// The robot's path: stops at fixed steps along a straight line (Alhashimi et al. 2021 eqs. 7-8),
/// or (kind driving) a pose every speed_m_per_scan along a route, stops = poses.
struct PathSpec {
  PathKind kind = PathKind::stops;  ///< stop and go (default) or driving
  Pose2 start;           ///< commanded (and true) pose of stop 0; stop and go moves along start.yaw
  double step_m = 0.30;  ///< commanded distance between consecutive stops, metres (stop and go)
  int stops = 10;        ///< number of stops K (driving: of poses along the route)
  /// 360-degree sweeps recorded at each stop (driving: per pose, default 1)
  int scans_per_stop = 10;
  /// std. dev. of the true position around the commanded one (eq. 8), metres (stop and go)
  double sigma_s_m = 0.0;
  /// std. dev. of the true heading around the commanded one, radians (stop and go)
  double sigma_psi_rad = 0.0;
  /// The true step is step_m (1 + step_error_fraction): an odometry scale error. 0 = off.
  /// Driving: the odometry reports every true step divided by (1 + step_error_fraction).
  double step_error_fraction = 0.0;
  DrivingSpec driving;  ///< route, speed and odometry noise (kind driving only)
};

/// Everything the simulator needs to produce a scan sequence.
struct Scene {
  std::string name = "scene";           ///< free text
  SensorSpec sensor;                    ///< the lidar
  PathSpec path;                        ///< where the robot stops
  std::vector<Cylinder> landmarks;      ///< poles to calibrate against (ids 1..L in this order)
  std::vector<Cylinder> clutter;        ///< other round objects (chair legs, bins): not landmarks
  std::vector<Segment> walls;           ///< straight surfaces (walls, boxes)
  bool publish_landmark_radius = true;  ///< write the landmarks' common radius into sequence.json
};

/// Commanded pose of stop k of a stop-and-go path: start + k * step along the start heading
/// (Alhashimi et al. 2021 eq. 7). (Driving paths: simulation::planStops.)
inline Pose2 commandedPose(const PathSpec& path, int stop) {
  Pose2 pose = path.start;
  pose.x_m += stop * path.step_m * std::cos(path.start.yaw_rad);
  pose.y_m += stop * path.step_m * std::sin(path.start.yaw_rad);
  return pose;
}

}  // namespace lidarcal
