// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What calibration consumes: landmarks seen from the stops of a sequence. Produced by the
// detector (from scans) or by the landmark-level simulator (Alhashimi et al. 2021 eqs. 3, 5, 8).

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "common/pose2.hpp"

namespace lidarcal {

/// BeamReading::beam when point i of one scan is not the same beam as point i of the other
/// scans of its stop (the beam count varies from scan to scan, e.g. YDLIDAR X4).
constexpr std::uint32_t kUnknownBeam = 0xFFFFFFFFu;

/// One raw beam reading on a landmark.
struct BeamReading {
  double angle_rad = 0.0;  ///< nominal beam angle in the sensor frame, radians
  double range_m = 0.0;    ///< raw reading, metres
  /// index of the point in its scan; kUnknownBeam when not comparable across scans
  std::uint32_t beam = 0;
  /// Return intensity as the sensor reports it (any unit); NaN when none was recorded (a
  /// recorded intensity of 0 or less counts as none: most drivers write 0 when they have none).
  double intensity = std::numeric_limits<double>::quiet_NaN();
  /// Whether it records an intensity (a finite value above 0).
  bool hasIntensity() const {
    return intensity > 0.0 && intensity < std::numeric_limits<double>::infinity();
  }
  /// Not on the landmark's circle: the beam beside it, read between the landmark and the
  /// background, kept as a mixed-pixel candidate (detectors/mixed_pixels.hpp). Default false.
  bool beside = false;
};

/// One landmark seen in one scan.
struct Sighting {
  std::size_t stop = 0;            ///< stop index (0-based)
  std::size_t scan = 0;            ///< scan index in the sequence (0-based)
  int landmark = 0;                ///< landmark id (> 0)
  double bearing_rad = 0.0;        ///< bearing of the fitted centre in the sensor frame, radians
  double centre_range_m = 0.0;     ///< distance to the fitted centre, metres
  double radius_m = 0.0;           ///< radius of the fitted circle, metres
  std::vector<BeamReading> beams;  ///< raw readings of the beams on the landmark, in beam order
};

/// A flat surface (wall) found in one scan: the line fitted to its points, in the sensor frame.
struct WallSighting {
  std::size_t stop = 0;     ///< stop index (0-based)
  std::size_t scan = 0;     ///< scan index in the sequence (0-based)
  double normal_rad = 0.0;  ///< direction from the sensor to the nearest point of the line, radians
  double distance_m = 0.0;  ///< perpendicular distance from the sensor to the line, metres
  std::vector<BeamReading> beams;  ///< raw readings of the beams on the wall, in beam order
  /// Which surface of its stop this is: sightings of one surface in the scans of a stop share
  /// an id (> 0; detectors/wall_tracks.hpp); 0 when not grouped. Default 0.
  int wall = 0;
};

/// Everything calibration needs from a sequence.
struct LandmarkObservations {
  std::vector<Pose2> commanded;             ///< commanded pose of each stop (VIEWPOINT)
  std::vector<Sighting> sightings;          ///< every landmark in every scan
  std::optional<double> landmark_radius_m;  ///< common landmark radius when known
  double range_min_m = 0.0;                 ///< sensor reporting window, metres
  double range_max_m = 1e9;                 ///< sensor reporting window, metres
  /// Walls seen at the stops that a reference measures a wall or a span at (empty otherwise).
  std::vector<WallSighting> walls;
};

/// Whether the beams of the sightings record a return intensity of at least two values (the
/// dark-surface noise term has a covariate to fit).
inline bool intensitiesVary(const LandmarkObservations& obs) {
  double first = 0.0;
  for (const auto& s : obs.sightings)
    for (const auto& b : s.beams) {
      if (!b.hasIntensity()) continue;
      if (first == 0.0)
        first = b.intensity;
      else if (b.intensity != first)
        return true;
    }
  return false;
}

}  // namespace lidarcal
