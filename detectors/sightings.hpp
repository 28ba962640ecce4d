// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// From detections in scans to what calibration consumes: each associated circle becomes a
// Sighting carrying the raw readings of its points (and, when asked, the mixed-pixel candidates
// beside it, mixed_pixels.hpp).

#include <cstdint>
#include <optional>

#include "common/landmark_observations.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/sequence.hpp"

namespace lidarcal::detectors {

/// What a sighting holds besides its circle's inliers.
struct SightingOptions {
  /// Also the beam just outside each end of the inliers when it reads clearly between the pole and
  /// the surface behind it, as its sighting's outermost reading: a mixed pixel. The
  /// detector leaves such readings out (they are off the circle), so without them a diagnosis
  /// cannot see mixed pixels on thin poles. Reads every scan with a sighting again. Default false.
  bool mixed_pixel_candidates = false;
  /// A candidate is kept only when none of the scans this many before or after it (the poses as
  /// commanded) reads a surface at its point within 2 t: what is behind a pole is seen again, a
  /// mixed pixel's reading falls anywhere between the pole and the background. Default 3.
  std::size_t persistence_scans = 3;
};

/// Re-reads the scans (one at a time) to collect the readings of every associated detection.
/// The sightings come by scan, and within a scan by landmark id, whatever the detector's order.
LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const SequenceDetections& det,
                                            const SightingOptions& options = {});

/// The same with the scans obtained from `load` (the loader given to detectSequence).
LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const SequenceDetections& det,
                                            const ScanLoader& load,
                                            const SightingOptions& options = {});

/// A point (sensor frame) as its beam's reading: the point's direction is its beam's direction
/// (the sensor measures range along it). An intensity of 0 (what a scan without one reads as)
/// is none recorded.
BeamReading beamReading(float x, float y, float intensity, std::uint32_t beam);

/// Point i of a scan as a reading (beam i); nullopt without a return.
std::optional<BeamReading> pointReading(const io::Scan& scan, long i);

}  // namespace lidarcal::detectors
