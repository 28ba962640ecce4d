// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Several 2D lidars on one vehicle: each sensor's planar mounting in the vehicle frame, and what
// a joint calibration of them consumes (the poles each sensor saw, at each of the vehicle's
// stops). Plain data: io/ reads and writes them, simulation/ draws them, calibration/ fits them.
//
// A beam at angle a in a sensor's own frame points, in the vehicle frame, at
//     yaw + s a,   s = +1 for a sensor mounted upright, -1 for one mounted upside down,
// from the sensor's origin (x, y): a lidar turned over keeps the direction of its x axis but
// sweeps clockwise as seen from above (its z axis points down).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "common/landmark_observations.hpp"
#include "common/pose2.hpp"

namespace lidarcal {

/// A sensor's planar mounting on the vehicle: its origin and the heading of its x axis in the
/// vehicle frame, and whether it is mounted upside down.
struct Mounting {
  double x_m = 0.0;  ///< origin x in the vehicle frame, metres. Default 0
  double y_m = 0.0;  ///< origin y in the vehicle frame, metres. Default 0
  /// heading of the sensor's x axis in the vehicle frame, radians. Default 0
  double yaw_rad = 0.0;
  /// z axis pointing down: beams sweep clockwise in the vehicle frame. Default false
  bool upside_down = false;
  /// height above the vehicle frame, metres (informative: the fit is planar). Default 0
  double z_m = 0.0;

  /// +1 upright, -1 upside down: the sign of a beam angle in the vehicle frame.
  double flip() const { return upside_down ? -1.0 : 1.0; }
  /// The planar pose (x, y, yaw) in the vehicle frame.
  Pose2 pose() const { return Pose2{x_m, y_m, yaw_rad}; }
  /// The direction, in the vehicle frame, of the beam at angle a of the sensor's own frame,
  /// radians.
  double beamDirection(double angle_rad) const { return yaw_rad + flip() * angle_rad; }
};

/// `b`'s mounting seen from `a`'s frame (planar; flips as they are): where sensor b sits in the
/// frame of sensor a when both are on one vehicle.
inline Pose2 relativeMounting(const Mounting& a, const Mounting& b) {
  return stepBetween(a.pose(), b.pose());
}

/// One sensor of a rig as calibration sees it.
struct RigSensor {
  std::string name;  ///< short name (e.g. "front"), unique in the rig
  Mounting prior;    ///< designed mounting (tf_static) or a guess; its flip is taken as known
  /// the mounting prior comes from a design (tf_static, --mount): used to associate and to start
  bool prior_known = false;
  double range_min_m = 0.0;  ///< the sensor's reporting window, metres
  double range_max_m = 1e9;  ///< the sensor's reporting window, metres
};

/// One pole seen by one sensor in one scan.
struct RigSighting {
  std::size_t sensor = 0;  ///< index into RigObservations::sensors
  std::size_t stop = 0;    ///< the vehicle's stop (index into RigObservations::vehicle)
  /// scan index, unique over the rig (repeated scans of a stop are pooled by it)
  std::size_t scan = 0;
  int pole = 0;                    ///< pole id (> 0), shared by every sensor that sees that pole
  std::vector<BeamReading> beams;  ///< raw readings of the beams on the pole, in beam order
};

/// Everything a joint calibration of several sensors needs.
struct RigObservations {
  std::vector<RigSensor> sensors;  ///< the lidars
  /// per stop: the vehicle's recorded pose (odometry, tf), or a starting guess
  std::vector<Pose2> vehicle;
  /// The recorded poses measure the vehicle (odometry, localisation): they enter as a prior.
  /// false: they are unknown (`vehicle` is where the fit starts; one stop per group of stops
  /// joined by poles is held there: the gauge).
  bool vehicle_known = false;
  std::vector<RigSighting> sightings;   ///< every pole seen by every sensor in every scan
  std::optional<double> pole_radius_m;  ///< common pole radius when known
};

}  // namespace lidarcal
