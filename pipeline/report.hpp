#pragma once
// The calibration report a newcomer reads: report.md with PNG plots (measured vs estimated
// distance with the fitted curve, noise vs range, the landmark map with raw and corrected
// points as in seed 000 Fig. 13, the order-selection table, the noise estimators side by side).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"
#include "pipeline/truth_eval.hpp"

namespace lidarcal::pipeline {

/// A model evaluated against the truth, for the comparison table.
struct ComparedModel {
  std::string name;         ///< e.g. "closed form (seed 000)", "oracle"
  CalibrationModel model;   ///< the model
  Evaluation evaluation;    ///< its correction of the evaluation sequence
};

struct ReportInputs {
  std::filesystem::path sequence;           ///< calibrated sequence
  std::size_t scans = 0, stops = 0;         ///< its size
  std::size_t detections = 0;               ///< associated circle detections
  const LandmarkObservations* observations = nullptr;  ///< what calibration saw
  const CalibrationModel* model = nullptr;  ///< the result
  std::vector<ComparedModel> compared;      ///< with truth: this model and its baselines
  std::string truth_note;                   ///< where the evaluation data came from
  std::string command;                      ///< command line that produced the report
};

/// Writes DIR/report.md and DIR/*.png (plots skipped with a note when gnuplot is missing).
void writeReport(const std::filesystem::path& dir, const ReportInputs& in);

}  // namespace lidarcal::pipeline
