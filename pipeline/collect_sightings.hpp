#pragma once
// From detections in scans to what calibration consumes: each associated circle becomes a
// Sighting carrying the raw readings of its points.

#include "common/landmark_observations.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/sequence.hpp"

namespace lidarcal::pipeline {

/// Re-reads the scans (one at a time) to collect the readings of every associated detection.
LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const detectors::SequenceDetections& det);

/// The same with the scans obtained from `load` (the loader given to detectSequence).
LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const detectors::SequenceDetections& det,
                                            const detectors::ScanLoader& load);

}  // namespace lidarcal::pipeline
