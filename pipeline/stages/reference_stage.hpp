// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Calibration and evaluation against what a user measured (REF.json, common/reference.hpp), as a
// composition: the targets of the reference distances found in the scans (poles: detectors/;
// walls: detectors/stop_walls.hpp), their beams turned into readings of known true distance, and
// the range model fitted to them (calibration/reference.hpp); the walls of wall-to-wall spans and
// the model fitted to the spans (calibration/span_calibration.hpp); surveyed landmarks matched to
// detected ones (detectors/survey_match.hpp) and held fixed in the self-calibration.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "calibration/filtering.hpp"
#include "calibration/inversion.hpp"
#include "calibration/reference.hpp"
#include "calibration/span_calibration.hpp"
#include "common/reference.hpp"
#include "detectors/sequence_detector.hpp"
#include "detectors/survey_match.hpp"
#include "io/sequence.hpp"
#include "pipeline/stages/stages.hpp"

namespace lidarcal::pipeline {

/// Loads scan i of `seq`; with `correct`, every point moved to its corrected distance first.
detectors::ScanLoader scanLoader(const io::Sequence& seq,
                                 const calibration::ReadingCorrector* correct = nullptr);

struct ReferenceObservations {
  /// poles (and walls at the stops a wall or a span is measured at)
  LandmarkObservations observations;
  /// each reference distance matched, with its known-distance readings
  calibration::ReferenceReadings known;
  calibration::SpanReadings spans;  ///< each span's two walls, with their beams
  std::size_t landmarks = 0;        ///< poles found by the detection
};

/// Detection settings for reference measurements: a pole measured at one stop counts (a static
/// sensor recorded at several distances sees each target position once).
detectors::SequenceDetectionConfig referenceDetection(detectors::SequenceDetectionConfig detection);

/// Finds the targets of `ref` in the scans `load` gives (poles: detection and association as in
/// calibrateSequence; walls: findWalls, with the detection's inlier threshold, at the stops a
/// wall or a span is measured at, grouped into the surfaces of each stop).
ReferenceObservations observeReference(const io::Sequence& seq, const Reference& ref,
                                       const detectors::SequenceDetectionConfig& detection,
                                       const detectors::ScanLoader& load,
                                       const StageProgress& on_scan = {});

/// What calibrate --reference shows about the spans: which walls each one was found between,
/// and how the model reproduces it (also when left out of the fit).
struct SpanReport {
  calibration::SpanReadings found;             ///< each span's two walls as found, with their beams
  std::vector<calibration::SpanCheck> checks;  ///< each entry of the fit: raw, fitted, left out
};

/// A sequence with the reference measurements of it, and how to detect and fit.
struct ReferencedSequence {
  const io::Sequence& seq;
  const Reference& ref;
  const std::filesystem::path& ref_file;  ///< named in errors
  const detectors::SequenceDetectionConfig& detection;
  const calibration::CalibrationConfig& config;
};

/// The range model from the reference distances and spans (method "reference"): with spans,
/// calibrateWithSpans over both; else calibrateWithReference. Throws DataError naming every
/// entry whose target was not found (with what to do).
SequenceCalibration calibrateSequenceWithReference(
    const ReferencedSequence& r, std::vector<calibration::ReferenceMatch>* matches = nullptr,
    const StageProgress& on_scan = {}, SpanReport* spans = nullptr);

/// Self-calibration (detection, triangulation, joint refinement) with the surveyed landmark
/// centres and the measured stop poses of `ref` held fixed (REF.json without distances). Each
/// surveyed landmark is matched to the nearest detected one (detectors::matchSurvey);
/// throws DataError naming the entries that match none.
SequenceCalibration calibrateSequenceWithSurvey(
    const ReferencedSequence& r, std::vector<detectors::SurveyMatch>* matches = nullptr,
    const NamedProgress& progress = {});

/// Throws DataError naming every reference distance whose target was not found (with what to do).
void requireEveryDistanceFound(const calibration::ReferenceReadings& known,
                               const std::filesystem::path& ref_file);

/// Throws InputError naming the first reference distance that matched the same target at the
/// same stop as an earlier one (its readings would count twice).
void requireDistinctTargets(const calibration::ReferenceReadings& known,
                            const std::filesystem::path& ref_file);

/// Throws DataError naming every span whose walls were not found, by the REF.json field at
/// fault (e.g. `spans[0].bearing_b_deg`), with the walls the stop does show.
void requireEverySpanFound(const calibration::SpanReadings& spans,
                           const std::filesystem::path& ref_file);

/// Stops with at least one measured distance (all of the sequence's: Alhashimi et al. 2016's fit on
/// the distances alone is the calibration; fewer: they join the self-calibration).
std::size_t measuredStops(const Reference& ref);

/// Self-calibration of the whole sequence with the measured distances in the same likelihood
/// (calibration::JointConfig::known_ranges: the tape's scale beside the poles' geometry) and the
/// surveyed landmarks and measured stops of `ref` held fixed as in calibrateSequenceWithSurvey.
/// For distances measured at only some stops. Method "joint+reference". Throws
/// InputError for --method closed-form, DataError for a distance whose target is not found.
SequenceCalibration calibrateSequenceWithDistancesAndSelf(
    const ReferencedSequence& r, std::vector<calibration::ReferenceMatch>* matches = nullptr,
    std::vector<detectors::SurveyMatch>* survey = nullptr, const NamedProgress& progress = {});

/// The matches as a Markdown table for stdout.
std::string surveyTable(const std::vector<detectors::SurveyMatch>& matches, const Reference& ref);

}  // namespace lidarcal::pipeline
