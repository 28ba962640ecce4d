// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One interval of a differential-drive robot that carries a 2D laser: what the wheels did and
// how far the laser moved by its own scan matching (a "sample" of Censi et al. 2013).
// Plain data shared by io/ (odometry tuples, docs/FORMAT.md) and odometry/ (the calibration).

namespace lidarcal {

/// Wheel speeds over an interval and the laser's scan-matched displacement over it.
struct OdometrySample {
  double duration_s = 0.0;            ///< length T of the interval, seconds (> 0)
  double left_wheel_rad_s = 0.0;      ///< average angular velocity of the left wheel, rad/s
  double right_wheel_rad_s = 0.0;     ///< average angular velocity of the right wheel, rad/s
  double scan_match_x_m = 0.0;        ///< laser displacement, forward in the laser's start frame, m
  double scan_match_y_m = 0.0;        ///< laser displacement, leftward in that frame, m
  double scan_match_theta_rad = 0.0;  ///< laser rotation over the interval, rad
};

}  // namespace lidarcal
