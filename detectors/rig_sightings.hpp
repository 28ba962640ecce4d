// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// From a rig sequence (io/rig.hpp) to what the joint calibration of several lidars consumes
// (common/rig.hpp): poles found in every scan of every sensor, then associated over the sensors
// and the vehicle's stops in the frame of the vehicle's poses, each sensor placed on the vehicle
// at its designed mounting (tf_static). Poles are matched by where they stand, not by the
// single-sensor association, because that one does not know a sensor is upside down.

#include <cstddef>
#include <string>
#include <vector>

#include "common/rig.hpp"
#include "detectors/scan_detector.hpp"
#include "io/rig.hpp"

namespace lidarcal::detectors {

struct RigDetectionSettings {
  DetectionConfig detection;  ///< per scan; its landmark_radius_m is the poles' radius (required)
  /// Retro-reflectors: points returning less than this intensity read as no return, so the
  /// reflectors stand alone in front of what is behind them. 0 (default): every point counts.
  double min_intensity = 0.0;
  /// A detection whose centre (vehicle pose and designed mounting) lies within this distance of
  /// a pole found so far belongs to it, metres. Default 0.3 (designs are off by centimetres).
  double associate_m = 0.3;
  /// A pole needs sightings in this many scans, over every sensor; fewer are dropped. Default 3.
  std::size_t min_scans = 3;
  void validate() const;  ///< throws InputError naming the option
};

/// Per sensor, what was found.
struct RigSensorDetections {
  std::size_t scans = 0;       ///< scans read
  std::size_t detections = 0;  ///< circles found
  std::size_t sightings = 0;   ///< of them, on a kept pole
  std::size_t poles = 0;       ///< kept poles it saw
};

struct RigCollected {
  RigObservations observations;              ///< for calibration::calibrateRig
  std::vector<RigSensorDetections> sensors;  ///< in the rig's sensor order
  std::size_t poles = 0;                     ///< poles kept
  std::size_t shared_poles = 0;              ///< of them, seen by two sensors or more
};

/// Detects and associates. Throws InputError for bad settings or a rig without a radius.
RigCollected collectRigObservations(const io::Rig& rig, const RigDetectionSettings& settings);

}  // namespace lidarcal::detectors
