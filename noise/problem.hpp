// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The data of noise estimation, checked and indexed once: stops, sensors, landmarks (dense
// indices), observations grouped by stop, commanded motions. Built from observations.csv and
// odometry.csv (docs/FORMAT.md); shared by the KL hill climbing (Sharma 2020) and the ML estimator.

#include <cstddef>
#include <vector>

#include "common/observation.hpp"

namespace lidarcal::noise {

struct NoiseProblem {
  int stops = 0;      ///< K: stops 0..K-1 (stop 0 is the start, the frame of the map)
  int sensors = 0;    ///< S: sensor ids 0..S-1
  int landmarks = 0;  ///< L: dense landmark indices 0..L-1
  std::vector<OdometryStep> odometry;  ///< K rows; row k is the commanded motion into stop k
  /// associated observations, sorted by stop (file order kept
  /// within a stop), `landmark` replaced by its dense index
  std::vector<Observation> observations;
  /// observations of stop k: [stop_begin[k], stop_begin[k+1]); K+1 entries
  std::vector<std::size_t> stop_begin;
  std::vector<int> landmark_ids;  ///< original id of each dense index
  /// observations with landmark -1, left out (no association)
  std::size_t skipped_unassociated = 0;
  std::vector<std::size_t> per_sensor;  ///< associated observations per sensor
};

/// Checks and indexes the data. Throws InputError when an observation refers to a stop beyond
/// the odometry, and DataError when a sensor id in 0..S-1 has no associated observation or
/// nothing is left after removing unassociated observations.
NoiseProblem makeNoiseProblem(const std::vector<Observation>& observations,
                              const std::vector<OdometryStep>& odometry);

}  // namespace lidarcal::noise
