// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The calibration report a newcomer reads: report.md with SVG plots (measured vs estimated
// distance with the fitted curve, noise vs range, the landmark map with raw and corrected
// points as in Alhashimi et al. 2021 Fig. 13, the order-selection table, the noise estimators side
// by side).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "calibration/reference.hpp"
#include "calibration/truth_evaluation.hpp"
#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"
#include "common/scene.hpp"

namespace lidarcal::pipeline {

/// A model evaluated against the truth, for the comparison table.
struct ComparedModel {
  std::string name;                    ///< e.g. "closed form (Alhashimi et al. 2021)", "oracle"
  CalibrationModel model;              ///< the model
  calibration::Evaluation evaluation;  ///< its correction of the evaluation sequence
};

struct ReportInputs {
  std::filesystem::path sequence;                      ///< calibrated sequence
  std::size_t scans = 0, stops = 0;                    ///< its size
  std::size_t detections = 0;                          ///< associated circle detections
  const LandmarkObservations* observations = nullptr;  ///< what calibration saw
  const CalibrationModel* model = nullptr;             ///< the result
  /// Calibration against reference measurements: the readings of known true distance it was
  /// fitted to (plotted instead of the landmarks' readings); null otherwise.
  const std::vector<calibration::KnownReading>* known = nullptr;
  /// What `correct` did to the returns of the written scans (null: the scans were not corrected).
  const calibration::FilteringStats* correction = nullptr;
  /// the policy they were corrected under
  calibration::Outside outside = calibration::kDefaultOutside;
  /// With truth: this model scored on the written scans first, then its baselines.
  std::vector<ComparedModel> compared;
  std::string truth_note;                ///< where the evaluation data came from
  std::vector<Cylinder> true_landmarks;  ///< simulator truth: drawn on the map when given
  std::string command;                   ///< command line that produced the report
};

/// Distances the model was fitted on: the smallest and largest estimated distance of the
/// landmark readings (0, 0 when there are none).
struct FittedRange {
  double min_m = 0.0, max_m = 0.0;
  bool contains(double d) const { return d >= min_m && d <= max_m; }
};

/// The x range of the distance plots: the fitted range with a margin of 10 % of its span (at
/// least 0.1 m), never below 0.
std::pair<double, double> plotRange(const FittedRange& fitted);

/// Writes DIR/report.md and DIR/*.svg (plots skipped with a note when gnuplot is missing):
/// readings and residuals before/after correction against the distance over the fitted range,
/// their histograms, noise against distance, and the map (estimated landmarks, numbered stops,
/// raw and corrected points, the true landmarks when given). The plot data (*.dat) and the
/// gnuplot script (plots.gp) stay beside the pictures.
void writeReport(const std::filesystem::path& dir, const ReportInputs& in);

}  // namespace lidarcal::pipeline
