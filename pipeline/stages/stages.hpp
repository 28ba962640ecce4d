// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The pipeline read like the paper: detect the poles in every scan and label them across
// stops, triangulate, fit the range model (closed form, then the joint refinement), and
// rewrite every scan with corrected ranges.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "calibration/calibrate.hpp"
#include "calibration/filtering.hpp"
#include "calibration/inversion.hpp"
#include "calibration/reference.hpp"
#include "common/calibration_model.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/pcd_scan.hpp"
#include "io/sequence.hpp"

namespace lidarcal::pipeline {

using StageProgress = std::function<void(std::size_t done, std::size_t total)>;
/// Progress of several named stages ("detect", "joint refinement"): steps done of the stage's
/// total.
using NamedProgress =
    std::function<void(const std::string& stage, std::size_t done, std::size_t total)>;

struct SequenceCalibration {
  detectors::SequenceDetections detections;  ///< circles per scan and landmark ids
  LandmarkObservations observations;         ///< what calibration consumed
  CalibrationModel model;                    ///< the result (status says whether it is usable)
  /// Calibration against reference measurements: the readings of known true distance the model
  /// was fitted to (a span's walls at the distances the model places them); empty otherwise.
  std::vector<calibration::KnownReading> known;
};

/// Detection, association and calibration of a sequence. `progress` hears of "detect" (scans,
/// twice the scans when the radius is estimated: the detector makes a second pass) and of the
/// calibration's own stages (config.progress, which is called as well).
/// `adjust`, when given, may change the calibration's configuration once the landmarks are
/// known (e.g. hold surveyed landmarks fixed by their ids).
using CalibrationAdjust =
    std::function<void(const detectors::SequenceDetections&, calibration::CalibrationConfig&)>;
SequenceCalibration calibrateSequence(const io::Sequence& seq,
                                      const detectors::SequenceDetectionConfig& detection,
                                      const calibration::CalibrationConfig& config,
                                      const NamedProgress& progress = {},
                                      const CalibrationAdjust& adjust = {});

/// A warning for calibrate/run when the scans of `seq` differ in their number of points (empty
/// when they agree). Not an error: some sensors (YDLIDAR X4) vary their beam count per sweep.
std::string beamCountWarning(const io::Sequence& seq);

/// Throws InputError when the model does not belong to the sequence's sensor (beam count, sensor
/// name, range limits) and DataError when its bias cannot be inverted unambiguously. Range limits
/// that differ on a sensor of the same name (or unnamed) are refused unless `force`; then the
/// returned text is a warning to print (empty when everything fits). With `outside` other than
/// extrapolate, f must be invertible over the fitted range only.
std::string checkModelFits(const CalibrationModel& model, const io::Sequence& seq,
                           const std::filesystem::path& model_file, bool force = false,
                           calibration::Outside outside = calibration::kDefaultOutside);

/// What a recording says about its sensor (sequence.json, a bag's LaserScan messages).
struct SensorFacts {
  std::optional<std::string> sensor_name;  ///< sensor name as import writes it; unset when unknown
  std::optional<double> range_min_m;       ///< smallest valid reading, metres; unset when unknown
  std::optional<double> range_max_m;       ///< largest valid reading, metres; unset when unknown
  std::string source;                      ///< where the facts come from (a file), for messages
  std::string noun = "recording";          ///< what the source is ("sequence", "bag"), for messages
};

/// checkModelFits without the beam count: status, sensor name, range limits (refused unless
/// `force`; the warning is returned) and invertibility. Same errors.
std::string checkModelFitsSensor(const CalibrationModel& model, const SensorFacts& facts,
                                 const std::filesystem::path& model_file, bool force = false,
                                 calibration::Outside outside = calibration::kDefaultOutside);

/// Throws InputError naming `where` when a scan of `beams` beams does not match the model's beam
/// count.
void checkModelBeams(const CalibrationModel& model, std::size_t beams, const std::string& where,
                     const std::filesystem::path& model_file);

/// Throws DataError when the model is not usable (diagnostics.status is not ok) or its bias
/// cannot be inverted unambiguously over the readings it corrects (the checks of checkModelFits
/// that need no recording: `export`).
/// The model's reading corrector (calibration::readingCorrector); throws InputError naming
/// --inversion when the model cannot be inverted that way (ML without the squared noise law).
calibration::ReadingCorrector modelCorrector(const CalibrationModel& model,
                                             calibration::InversionMethod method,
                                             calibration::Outside outside,
                                             const std::filesystem::path& model_file);

void checkModelInvertible(const CalibrationModel& model, const std::filesystem::path& model_file,
                          calibration::Outside outside = calibration::kDefaultOutside);

/// What correcting a sequence or a bag did to its returns, and in how many scans.
struct CorrectionStats : calibration::FilteringStats {
  std::size_t scans = 0;  ///< scans (or LaserScan messages) corrected
};

/// How a sequence's scans are corrected and written.
struct SequenceCorrection {
  calibration::InversionMethod method = calibration::InversionMethod::ls;
  calibration::Outside outside = calibration::kDefaultOutside;
  io::PcdEncoding encoding = io::PcdEncoding::binary;
  /// Scans corrected side by side (0: the machine's cores, at most 8); the files and counts do
  /// not depend on it.
  int threads = 0;
};

/// Streams every scan through the filtering stage into `out_dir` (an existing, empty staging
/// directory); copies sequence.json.
CorrectionStats correctSequence(const io::Sequence& seq, const CalibrationModel& model,
                                const std::filesystem::path& out_dir, const SequenceCorrection& how,
                                const StageProgress& on_scan = {});

}  // namespace lidarcal::pipeline
