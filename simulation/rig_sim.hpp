// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Landmark-level simulation of several 2D lidars on one vehicle: the vehicle stops at given
// poses (each true pose around its recorded one, Alhashimi et al. 2021 eq. 8) or drives along a
// route with noisy odometry; each sensor, at its mounting on the vehicle, sweeps its beam grid,
// and every beam that meets a pole reads f_s(d) + sigma_s(d) e (Alhashimi et al. 2021 eq. 3)
// with the sensor's own range model. No scans and no detector: the sightings carry the truth's
// pole ids. What calibrateRig() consumes, with the truth beside it.

#include <cstdint>
#include <string>
#include <vector>

#include "common/rig.hpp"
#include "common/scene.hpp"
#include "common/truth.hpp"

namespace lidarcal::simulation {

/// One simulated lidar of the rig.
struct RigSimSensor {
  std::string name = "lidar";  ///< unique in the rig
  Mounting mounting;           ///< true mounting on the vehicle (flip included)
  Mounting design;   ///< what the calibration is told (its prior); flip taken from `mounting`
  RangeModel model;  ///< true bias, noise law and reporting window
  /// beam 0's angle in the sensor frame, radians. Default -135 deg
  double angle_min_rad = -2.356194490192345;
  /// step between beams, radians. Default 0.25 deg
  double angle_increment_rad = 0.004363323129985824;
  int beams = 1081;  ///< beams per sweep. Default 1081 (270 deg)
};

struct RigSimConfig {
  std::vector<RigSimSensor> sensors;  ///< the lidars
  std::vector<Cylinder> poles;        ///< ids 1..P in this order
  /// Stop and go: the recorded (commanded) vehicle pose of each stop; the true one is drawn
  /// around it with sigma_s_m per coordinate and sigma_psi_rad in heading. Used unless
  /// `driving` is set.
  std::vector<Pose2> stops;
  double sigma_s_m = 0.0;      ///< std. dev. of each true stop coordinate, metres. Default 0
  double sigma_psi_rad = 0.0;  ///< std. dev. of each true stop heading, radians. Default 0
  int scans_per_stop = 10;     ///< sweeps per sensor at each stop. Default 10
  /// A vehicle that never stops: path.kind driving (route, speed, odometry noise; planStops).
  PathSpec driving;
  /// drive along `driving` instead of stopping at `stops`. Default false
  bool use_driving = false;
  bool vehicle_known = true;  ///< the recorded poses go to the calibration as a prior. Default true
  bool publish_radius = true;  ///< tell the calibration the poles' common radius. Default true
  bool occlusion = true;       ///< a beam stops at the first pole it meets. Default true
};

struct RigSimSample {
  RigObservations obs;           ///< what the calibration sees
  std::vector<TruthStop> stops;  ///< recorded and true vehicle poses
};

/// One draw. Randomness: stream 0 for the true poses, one stream per scan and sensor for the
/// readings.
RigSimSample simulateRig(const RigSimConfig& config, std::uint64_t seed);

}  // namespace lidarcal::simulation
