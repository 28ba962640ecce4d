// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A simulated range sweep: a static sensor looking at one pole placed at a series of measured
// distances, one stop per distance, the way the Hokuyo UST-30LX sweep of ../shared/data was
// recorded (docs/results/real-sensors.md). The pole's beams are ray-cast at the landmark level
// (simulation/landmark_level.hpp, no scans, no detector: fast enough for hundreds of seeds), and
// the tape distances a user would write into REF.json come with it, each with a tape error.
// Used by the tests and the benchmark of the predictive intervals (bench/predictive_coverage.cpp).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/landmark_observations.hpp"
#include "common/range_effects.hpp"
#include "common/range_model.hpp"
#include "common/reference.hpp"

namespace lidarcal::simulation {

struct RangeSweepConfig {
  /// the pole's centre distance at each stop, metres (one stop each)
  std::vector<double> distances_m;
  double radius_m = 0.045;  ///< the pole's radius, metres. Default 0.045 (the Hokuyo's reflector)
  std::size_t scans_per_stop = 10;  ///< scans recorded at each stop. Default 10
  /// the beam grid's step, radians. Default 0.25 degrees
  double angle_increment_rad = 0.004363323129985824;
  RangeModel model;      ///< the sensor's bias polynomial, noise law and range window
  RangeEffects effects;  ///< e.g. a ripple of the bias (RangeEffects::ripple_amplitude_m)
  /// standard deviation of the error drawn for each tape distance, metres. Default 0
  double tape_error_m = 0.0;
  /// sigma_m written into each REF.json entry, metres. Default 0 (exact)
  double stated_sigma_m = 0.0;
  void validate() const;  ///< throws std::invalid_argument
};

struct RangeSweep {
  LandmarkObservations obs;  ///< the pole's sightings with their beams, one stop per distance
  /// one landmark entry per stop: the tape distance (with its error), bearing 0
  Reference reference;
  /// the pole's true centre distance at each stop (distances_m)
  std::vector<double> true_distance_m;
};

/// One draw: randomness from `seed` (the readings as simulateLandmarkLevel draws them; the tape
/// errors from a stream of their own).
RangeSweep simulateRangeSweep(const RangeSweepConfig& config, std::uint64_t seed);

}  // namespace lidarcal::simulation
