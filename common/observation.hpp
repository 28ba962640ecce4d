// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Landmark observations and odometry of a robot that stops, looks at landmarks with one or
// more range-bearing sensors, and moves on (docs/FORMAT.md: observations.csv, odometry.csv).
// Plain data shared by io/, simulation/ and calibration/ (noise estimation).

#include <vector>

namespace lidarcal {

/// One range-bearing reading of a landmark by one sensor at one stop.
struct Observation {
  int stop = 0;          ///< stop index (0-based; matches odometry.csv)
  int sensor = 0;        ///< sensor index (0-based)
  int landmark = -1;     ///< landmark id (>= 0), or -1 when the association is unknown
  double range_m = 0.0;  ///< measured range, metres
  /// measured bearing in the robot frame, radians, counter-clockwise from robot x
  double bearing_rad = 0.0;
};

/// Commanded motion into a stop, expressed in the robot frame of the previous stop.
struct OdometryStep {
  int stop = 0;             ///< the stop reached by this motion (stop 0 is the start: zero motion)
  double dx_m = 0.0;        ///< forward displacement, metres
  double dy_m = 0.0;        ///< leftward displacement, metres
  double dtheta_rad = 0.0;  ///< heading change, radians
};

/// Gaussian noise of one range-bearing sensor: reading = truth + N(mean, var) per component.
struct SensorNoise {
  double range_mean_m = 0.0;      ///< range bias, metres
  double range_var_m2 = 0.0;      ///< range noise variance, m^2
  double bearing_mean_rad = 0.0;  ///< bearing bias, radians
  double bearing_var_rad2 = 0.0;  ///< bearing noise variance, rad^2
};

/// Zero-mean Gaussian process (motion) noise added to each commanded motion, robot frame.
struct ProcessNoise {
  double dx_var_m2 = 0.0;        ///< variance of the forward displacement error, m^2
  double dy_var_m2 = 0.0;        ///< variance of the leftward displacement error, m^2
  double dtheta_var_rad2 = 0.0;  ///< variance of the heading change error, rad^2
};

/// A full noise setting: one SensorNoise per sensor (index = sensor id) and the process noise.
struct NoiseSetting {
  std::vector<SensorNoise> sensors;  ///< per sensor, indexed by sensor id
  ProcessNoise process;              ///< motion noise
};

}  // namespace lidarcal
