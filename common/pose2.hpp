// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Planar pose of the sensor in the world frame.

#include <cmath>

namespace lidarcal {

/// Planar pose: position (metres) and heading (radians, counter-clockwise from world x).
struct Pose2 {
  double x_m = 0.0;      ///< x position, metres
  double y_m = 0.0;      ///< y position, metres
  double yaw_rad = 0.0;  ///< heading, radians

  /// Maps a point from the sensor frame to the world frame.
  void toWorld(double sx, double sy, double& wx, double& wy) const {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    wx = x_m + c * sx - s * sy;
    wy = y_m + s * sx + c * sy;
  }
  /// Maps a point from the world frame to the sensor frame.
  void toSensor(double wx, double wy, double& sx, double& sy) const {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    const double dx = wx - x_m, dy = wy - y_m;
    sx = c * dx + s * dy;
    sy = -s * dx + c * dy;
  }
};

/// Wraps an angle to (-pi, pi].
inline double wrapAngle(double a_rad) {
  constexpr double kPi = 3.14159265358979323846;
  a_rad = std::fmod(a_rad + kPi, 2.0 * kPi);
  if (a_rad <= 0.0) a_rad += 2.0 * kPi;
  return a_rad - kPi;
}

/// Pose b seen from pose a: the step from a to b in a's frame.
inline Pose2 stepBetween(const Pose2& a, const Pose2& b) {
  Pose2 d;
  a.toSensor(b.x_m, b.y_m, d.x_m, d.y_m);
  d.yaw_rad = wrapAngle(b.yaw_rad - a.yaw_rad);
  return d;
}

/// Pose a followed by the step d (given in a's frame).
inline Pose2 compose(const Pose2& a, const Pose2& d) {
  Pose2 out;
  a.toWorld(d.x_m, d.y_m, out.x_m, out.y_m);
  out.yaw_rad = wrapAngle(a.yaw_rad + d.yaw_rad);
  return out;
}

constexpr double kPi = 3.14159265358979323846;
constexpr double deg2rad(double deg) { return deg * kPi / 180.0; }
constexpr double rad2deg(double rad) { return rad * 180.0 / kPi; }

}  // namespace lidarcal
