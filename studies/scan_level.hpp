// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Scan-level draws for the Monte Carlo study: the layout becomes a scene, every scan is
// ray-cast (simulation/simulator.hpp), and the landmarks are found by the detector and
// associated across stops (detectors::detectSequence) on scans held in memory, then turned
// into landmark observations the way the pipeline does it from files. No file is written.

#include <cstdint>
#include <vector>

#include "common/scene.hpp"
#include "studies/draw.hpp"

namespace lidarcal::studies {

struct TrialConfig;

struct ScanLevelConfig {
  int beams = 360;  ///< beams per 360-degree sweep
  /// a detected landmark is the true one whose centre is nearest, within this, metres
  double match_distance_m = 0.5;
  void validate() const;  ///< throws std::invalid_argument
};

/// The scan-level settings of a trial configuration.
ScanLevelConfig scanLevelConfig(const TrialConfig& config);

/// One scan-level draw. `detect` true: detection and association in the loop, ids as detected
/// and matched to the layout afterwards (Draw::true_id). `detect` false: every beam that hits a
/// landmark, grouped by the truth (a test set needs no detector).
Draw drawScanLevel(const std::vector<Cylinder>& layout, const PathSpec& path,
                   const RangeModel& sensor, const ScanLevelConfig& config, std::uint64_t seed,
                   bool detect);

}  // namespace lidarcal::studies
