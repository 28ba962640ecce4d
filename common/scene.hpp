#pragma once
// A simulated world: a 2D scanning lidar on a robot that stops along a straight line among
// vertical cylinders (landmarks, clutter) and wall segments. Plain data; io/scene_io reads it
// from JSON, simulation/ ray-casts it.

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
  double range_offset_m = 0.0;  ///< added to every reading on this surface (reflectivity, colour), metres
};

/// A straight wall segment in the world frame.
struct Segment {
  double x0_m = 0.0, y0_m = 0.0;  ///< first end point, metres
  double x1_m = 1.0, y1_m = 0.0;  ///< second end point, metres
  double range_offset_m = 0.0;    ///< added to every reading on this surface (reflectivity, colour), metres
};

/// The scanning lidar: beam layout, range model and angular noise.
struct SensorSpec {
  std::string name = "simulated-lidar";  ///< written to sequence.json
  int beams = 360;                       ///< beams per scan (one 360-degree sweep)
  double angle_min_rad = 0.0;            ///< angle of beam 0 in the sensor frame, radians
  double angle_increment_rad = 0.017453292519943295;  ///< angular step between beams (1 degree)
  RangeModel range;                      ///< bias f(d), noise law and range window [min, max]
  double bearing_noise_rad = 0.0;        ///< std. dev. of per-beam angular jitter, radians
  double mount_yaw_rad = 0.0;            ///< lidar zero angle rotated against the robot, radians
  RangeEffects effects;                  ///< effects beyond the seeds' model (all off by default)
};

/// The robot's path: stops at fixed steps along a straight line (seed 000 eqs. 7-8).
struct PathSpec {
  Pose2 start;                 ///< commanded pose of stop 0; the robot moves along start.yaw
  double step_m = 0.30;        ///< commanded distance between consecutive stops, metres
  int stops = 10;              ///< number of stops K
  int scans_per_stop = 10;     ///< 360-degree sweeps recorded at each stop
  double sigma_s_m = 0.0;      ///< std. dev. of the true position around the commanded one (eq. 8), metres
  double sigma_psi_rad = 0.0;  ///< std. dev. of the true heading around the commanded one, radians
  /// The true step is step_m (1 + step_error_fraction): an odometry scale error. 0 = off.
  double step_error_fraction = 0.0;
};

/// Everything the simulator needs to produce a scan sequence.
struct Scene {
  std::string name = "scene";          ///< free text
  SensorSpec sensor;                   ///< the lidar
  PathSpec path;                       ///< where the robot stops
  std::vector<Cylinder> landmarks;     ///< poles to calibrate against (ids 1..L in this order)
  std::vector<Cylinder> clutter;       ///< other round objects (chair legs, bins): not landmarks
  std::vector<Segment> walls;          ///< straight surfaces (walls, boxes)
  bool publish_landmark_radius = true; ///< write the landmarks' common radius into sequence.json
};

/// Commanded pose of stop k: start + k * step along the start heading (seed 000 eq. 7).
inline Pose2 commandedPose(const PathSpec& path, int stop) {
  Pose2 pose = path.start;
  pose.x_m += stop * path.step_m * std::cos(path.start.yaw_rad);
  pose.y_m += stop * path.step_m * std::sin(path.start.yaw_rad);
  return pose;
}

}  // namespace lidarcal
