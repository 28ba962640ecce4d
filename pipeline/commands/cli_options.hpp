// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Command-line options shared by `calibrate` and `run`, mapped into the stage configs.

#include <memory>
#include <string>
#include <vector>

#include "calibration/calibrate.hpp"
#include "calibration/filtering.hpp"
#include "detectors/sequence_detector.hpp"

namespace CLI {
class App;
}

namespace lidarcal::pipeline {

struct CalibrationOptions {
  std::string method = "joint";
  int max_order = 4;
  std::string order_rule = "aic";
  std::string joint_order_rule = "aic-parsimonious";
  std::string noise = "squared";
  double sigma_s_m = 0.02;
  double sigma_psi_deg = 0.5;
  double sigma_theta_deg = 1.0;
  double radius_m = 0.0;  // 0: from sequence.json or estimated
  int min_stops = 3;
  // A, B of the detector's t(r) = A + B r^2, metres
  std::vector<double> inlier_threshold{0.01, 0.005};
  std::string motion_prior = "auto";  // auto, on, off (JointConfig::motion)
  // comma-separated effect terms of the joint refinement (lidarcal diagnose's names)
  std::string effects;
  int threads = 0;  // threads (detection, the joint refinement's orders, correction); 0: automatic
};

/// --threads: the threads for the work that runs side by side, which `work` names for the help
/// (0, the default: the machine's cores, at most 8).
void addThreadsOption(CLI::App* app, int& threads, const std::string& work);

/// --inlier-threshold A,B: the threshold t(r) = A + B r^2 (metres) of the circle and line fits.
void addInlierThresholdOption(CLI::App* app, std::vector<double>& threshold);
/// Sets the detection's threshold from the option's values (InputError when A is not > 0).
void applyInlierThreshold(const std::vector<double>& threshold,
                          detectors::DetectionConfig& detection);

/// Adds the options to a subcommand.
void addCalibrationOptions(CLI::App* app, const std::shared_ptr<CalibrationOptions>& o);
/// Maps them into the stage configs (throws InputError for a bad value).
calibration::CalibrationConfig calibrationConfig(const CalibrationOptions& o);
detectors::SequenceDetectionConfig detectionConfig(const CalibrationOptions& o);

/// How readings are corrected: `correct`, `export` and the ROS node share these options.
struct CorrectionOptions {
  std::string inversion = "ls";  ///< --inversion ls|ml
  /// --outside keep|extrapolate|drop
  std::string outside = calibration::toString(calibration::kDefaultOutside);
  calibration::InversionMethod method() const;
  calibration::Outside outsidePolicy() const;
};
/// Adds --inversion and --outside (with their help text) to a subcommand.
void addCorrectionOptions(CLI::App* app, const std::shared_ptr<CorrectionOptions>& o);

}  // namespace lidarcal::pipeline
