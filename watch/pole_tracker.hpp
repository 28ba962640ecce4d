// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Poles followed from scan to scan on a robot that never stops: each scan's circles
// (detectors/scan_detector.hpp) linked to the poles seen before in the world frame of the scans'
// poses (detectors/association.hpp's StopLinker, every scan its own stop, the reach growing with
// the travel since a pole was last seen), as `detect` does for a whole sequence, one scan at a
// time. Memory holds the poles seen lately, not the scans.

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "common/landmark_observations.hpp"
#include "common/pose2.hpp"
#include "detectors/association.hpp"
#include "io/import.hpp"

namespace lidarcal::watch {

/// A pole's track; merged tracks take the number of the track they join.
using PoleId = std::uint64_t;

/// One pole in one scan: its circle and the raw readings of its beams.
struct PoleSighting {
  PoleId pole = 0;                 ///< its track
  double bearing_rad = 0.0;        ///< bearing of the fitted centre, sensor frame, radians
  double centre_range_m = 0.0;     ///< distance to the fitted centre, metres (raw readings)
  double radius_m = 0.0;           ///< radius of the fitted circle, metres
  std::vector<BeamReading> beams;  ///< the readings on the pole as the sensor gave them
};

/// What the tracker made of one scan.
struct TrackedScan {
  std::vector<PoleSighting> poles;  ///< the circles found, each with its track
  std::size_t circles = 0;          ///< circles the detector accepted (some may join no track)
  /// Tracks found to be one pole at this scan: (merged track, the track it joined), in order.
  std::vector<std::pair<PoleId, PoleId>> merged;
};

class PoleTracker {
 public:
  /// `detection`: the per-scan detector; `association`: the linking (drift_per_m > 0 for a robot
  /// that never stops). Throws std::invalid_argument when either is invalid.
  PoleTracker(const detectors::DetectionConfig& detection,
              const detectors::AssociationConfig& association);

  /// Detects the poles of scan `index` (strictly increasing from call to call) and links them.
  /// `scan.pose` is the sensor's pose in the world frame.
  TrackedScan track(const io::RawScan& scan, std::size_t index);

  /// Tracks held now (poles seen lately and objects that may still become poles).
  std::size_t tracksAlive() const { return linker_.alive(); }

 private:
  detectors::DetectionConfig detection_;
  detectors::AssociationConfig association_;
  detectors::StopLinker linker_;
};

}  // namespace lidarcal::watch
