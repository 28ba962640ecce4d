// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What a user with a tape measure would write into REF.json for a simulated sequence: the
// distance from the sensor's true position at each stop to the centre of every pole it sees
// whole. Used by the tests and benchmarks of `calibrate --reference`
// (docs/results/standard-errors.md); the truth stands in for the tape.

#include <cstdint>

#include "common/reference.hpp"
#include "common/truth.hpp"

namespace lidarcal {

struct TapeConfig {
  double max_distance_m = 4.0;  ///< poles farther than this are not measured, metres. Default 4
  /// A pole is skipped when a nearer one covers it or comes within this angle of its edge,
  /// radians. Default 2 degrees (two beams of a 1-degree lidar).
  double margin_rad = 0.0349;
  /// standard deviation of the tape error added to each distance, metres. Default 0 (exact)
  double sigma_m = 0.0;
  std::uint64_t seed = 0;  ///< seed of the tape errors
};

/// One `landmark` distance with its bearing (sensor frame) per visible pole and stop, in stop
/// order; sigma_m of each entry is config.sigma_m (at least 0.1 mm).
Reference tapeReference(const Truth& truth, const TapeConfig& config = {});

}  // namespace lidarcal
