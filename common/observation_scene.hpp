// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// An observation-level scene (`"kind": "observations"`): landmarks as points, a robot driven by
// commanded motions with process noise, and range-bearing sensors each with its own Gaussian
// noise. simulation/observation_sim turns it into observations.csv + odometry.csv (Sharma 2020's
// experimental setting, ch. 5). Plain data; io/noise_json reads it.

#include <limits>
#include <string>
#include <vector>

#include "common/observation.hpp"
#include "common/pose2.hpp"

namespace lidarcal {

/// A range-bearing sensor mounted at the robot origin, aligned with the robot.
struct RangeBearingSensor {
  std::string name = "sensor";  ///< free text
  SensorNoise noise;            ///< true noise: reading = truth + N(mean, var), per component
  double min_range_m = 0.0;     ///< landmarks closer than this are not seen, metres
  /// landmarks farther are not seen, metres
  double max_range_m = std::numeric_limits<double>::infinity();
  double fov_rad = 2.0 * kPi;  ///< field of view centred on robot x, radians (2 pi: all around)
};

/// A point landmark in the world frame. Its id is its index in ObservationScene::landmarks.
struct PointLandmark {
  double x_m = 0.0;  ///< x, metres
  double y_m = 0.0;  ///< y, metres
};

/// One commanded motion, repeated `count` times in a row.
struct MotionSpec {
  double dx_m = 0.0;        ///< forward, metres (robot frame)
  double dy_m = 0.0;        ///< leftward, metres (robot frame)
  double dtheta_rad = 0.0;  ///< heading change, radians
  int count = 1;            ///< how many consecutive stops use this motion (>= 1)
};

/// Everything the observation simulator needs.
struct ObservationScene {
  std::string name = "observations";        ///< free text
  std::vector<RangeBearingSensor> sensors;  ///< sensor ids 0..S-1 in this order (>= 1 sensor)
  ProcessNoise process;                     ///< true motion noise
  std::vector<PointLandmark> landmarks;     ///< landmark ids 0..L-1 in this order (>= 1)
  Pose2 start;                              ///< true and believed pose of stop 0
  std::vector<MotionSpec> motions;          ///< one lap of commanded motions
  int repeat = 1;                           ///< laps (>= 1); stops = 1 + repeat * sum(count)
};

/// The true noise setting of a scene (its sensors' noise and the process noise).
inline NoiseSetting trueNoise(const ObservationScene& scene) {
  NoiseSetting n;
  for (const auto& s : scene.sensors) n.sensors.push_back(s.noise);
  n.process = scene.process;
  return n;
}

}  // namespace lidarcal
