// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Samples of a simulated drive with a known truth: wheel speeds drawn from a mix of motions,
// the laser displacement the motion model predicts from the true parameters, plus Gaussian
// scan-matching noise and, optionally, gross scan-matching failures. For tests and studies of
// the calibration (the model's assumptions hold exactly: the wheel speeds carry no error).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/odometry_sample.hpp"
#include "odometry/motion_model.hpp"

namespace lidarcal::odometry {

/// The kinds of motion a simulated drive mixes; each sample draws one of the enabled kinds.
struct MotionMix {
  bool straight = true;  ///< both wheels alike, forward or backward
  bool rotation = true;  ///< turning in place, either direction
  bool pivot = true;     ///< one wheel still, the other forward or backward
  bool arc = true;       ///< both wheels forward (or backward) at different speeds
};

struct SimulationSettings {
  /// the robot's true parameters (default: near those of Censi et al. 2013's configuration B)
  OdometryParameters truth{0.0206, 0.0207, 0.088, -0.0026, 0.0058, -1.558};
  std::size_t samples = 1000;      ///< samples to draw
  double duration_s = 0.8;         ///< interval T, seconds (each drawn within +-5 %)
  double wheel_speed_rad_s = 0.5;  ///< faster wheel's speed, rad/s (each drawn in 50-100 %)
  MotionMix mix;                   ///< the motions drawn
  double sigma_x_m = 0.001;        ///< scan-matching noise, forward, metres (standard deviation)
  double sigma_y_m = 0.001;        ///< scan-matching noise, leftward, metres
  double sigma_theta_rad = 0.002;  ///< scan-matching noise, rotation, radians
  /// fraction of samples whose scan match failed: an extra error uniform in +-0.1 m (x, y) and
  /// +-0.2 rad (theta)
  double outlier_fraction = 0.0;
  std::uint64_t seed = 1;  ///< base seed (common/rng.hpp)
};

/// Draws `settings.samples` samples. Deterministic for a seed.
std::vector<OdometrySample> simulateSamples(const SimulationSettings& settings);

}  // namespace lidarcal::odometry
