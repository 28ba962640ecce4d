#pragma once
// Calibration and evaluation against what a user measured (REF.json, common/reference.hpp):
// the targets of the reference distances found in the scans, their beams turned into readings
// of known true distance, and the range model fitted to them (calibration/reference.hpp).

#include <cstddef>
#include <vector>

#include "calibration/filtering.hpp"
#include "calibration/inversion.hpp"
#include "calibration/reference.hpp"
#include "common/reference.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/sequence.hpp"
#include "pipeline/stages.hpp"

namespace lidarcal::pipeline {

/// A model ready to correct scans: its inverter and the readings it corrects.
struct ScanCorrection {
  calibration::RangeInverter inverter;
  calibration::CorrectionWindow window;
};

/// Loads scan i of `seq`; with `correct`, every point moved to its corrected distance first.
detectors::ScanLoader scanLoader(const io::Sequence& seq, const ScanCorrection* correct = nullptr);

struct ReferenceObservations {
  LandmarkObservations observations;       ///< poles (and walls at the stops a wall is measured at)
  calibration::ReferenceReadings known;    ///< each reference distance matched, with its known-distance readings
  std::size_t landmarks = 0;               ///< poles found by the detection
};

/// Detection settings for reference measurements: a pole measured at one stop counts (a static
/// sensor recorded at several distances sees each target position once).
detectors::SequenceDetectionConfig referenceDetection(detectors::SequenceDetectionConfig detection);

/// Finds the targets of `ref` in the scans `load` gives (poles: detection and association as in
/// calibrateSequence; walls: findWalls at the stops a wall is measured at).
ReferenceObservations observeReference(const io::Sequence& seq, const Reference& ref,
                                       const detectors::SequenceDetectionConfig& detection,
                                       const detectors::ScanLoader& load, const StageProgress& on_scan = {});

/// The range model from the reference distances (method "reference"); throws DataError naming
/// every entry whose target was not found (with what to do).
SequenceCalibration calibrateSequenceWithReference(const io::Sequence& seq, const Reference& ref,
                                           const std::filesystem::path& ref_file,
                                           const detectors::SequenceDetectionConfig& detection,
                                           const calibration::CalibrationConfig& config,
                                           std::vector<calibration::ReferenceMatch>* matches = nullptr,
                                           const StageProgress& on_scan = {});

}  // namespace lidarcal::pipeline
