// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Observation-level simulator (Sharma 2020 ch. 3.5 and ch. 5): the true trajectory follows the
// commanded motions plus process noise, x_k = x_{k-1} (+) (u_k + w_k), w_k ~ N(0, diag(q));
// each sensor reads every landmark within its range window and field of view as
//   range   = |l - p_k| + range_mean + sqrt(range_var) e1,
//   bearing = wrap(atan2(l - p_k) - theta_k + bearing_mean + sqrt(bearing_var) e2),  e ~ N(0, 1).
// Readings are not clipped (a very noisy range can come out negative).
//
// Randomness: process noise from stream 0 (three normals per motion), sensor s from stream
// 1 + s (two normals per stop and landmark, drawn whether or not the landmark is seen), so
// changing one sensor's noise or visibility leaves the others' readings unchanged.

#include <cstdint>
#include <vector>

#include "common/observation.hpp"
#include "common/observation_scene.hpp"
#include "common/pose2.hpp"

namespace lidarcal::simulation {

/// Output of the observation simulator.
struct ObservationSimulation {
  std::vector<Observation> observations;  ///< ordered by stop, sensor, landmark
  std::vector<OdometryStep> odometry;     ///< one row per stop (stop 0: zero motion)
  std::vector<Pose2> true_poses;          ///< true pose of every stop
};

/// The commanded motions of every stop (stop 0: zero), laps unrolled.
std::vector<OdometryStep> commandedMotions(const ObservationScene& scene);

/// Composes a pose with a motion given in its own frame.
Pose2 compose(const Pose2& pose, double dx_m, double dy_m, double dtheta_rad);

/// Simulates the scene with `seed`.
ObservationSimulation simulateObservations(const ObservationScene& scene, std::uint64_t seed);

}  // namespace lidarcal::simulation
