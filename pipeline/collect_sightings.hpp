#pragma once
// From detections in scans to what calibration consumes: each associated circle becomes a
// Sighting carrying the raw readings of its points.

#include <optional>

#include "common/landmark_observations.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/sequence.hpp"

namespace lidarcal::pipeline {

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
LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const detectors::SequenceDetections& det,
                                            const SightingOptions& options = {});

/// The same with the scans obtained from `load` (the loader given to detectSequence).
LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const detectors::SequenceDetections& det,
                                            const detectors::ScanLoader& load, const SightingOptions& options = {});

/// The reading of the point next to a circle's outermost inlier `edge` on the side `step` (+1 or
/// -1; points taken modulo the scan's size), marked `beside`, when it lies between the pole and
/// what is behind it: at least the pole's radius and twice the inlier threshold t beyond the
/// inlier's reading, and 3 t short of the background, which is the surface of the next two
/// points out extended to this beam (the nearer of that line and the next point's reading). The
/// four points must be evenly spaced in angle (within a quarter of a step), so a cloud without
/// its missing returns is judged right too. A clean scan puts almost no reading there: a beam
/// past the pole reads the background, one on it reads the pole. A pole across a full scan's seam
/// is looked beside too: its inliers run along the arc (n-2, n-1, 0, 1), so their ends are its edges.
std::optional<BeamReading> readingBetweenPoleAndBackground(const io::Scan& scan, int edge, int step, double radius_m,
                                                           const detectors::DetectionConfig& config);

}  // namespace lidarcal::pipeline
