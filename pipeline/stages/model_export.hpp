// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// `lidarcal export`: a model.json in the forms a ROS driver can use without lidarcal's code
// (docs/FORMAT.md#model-for-drivers-lidarcal-export).
//   yaml: ROS parameters: the bias polynomial, the readings it corrects, the inversion.
//   lut:  CSV lookup table reading_m -> range_m over those readings, each row what `correct`
//         gives for that reading (calibration::ReadingCorrector).

#include <string>

#include "calibration/filtering.hpp"
#include "common/calibration_model.hpp"

namespace lidarcal::pipeline {

struct ExportConfig {
  /// ls (default) or ml, as `correct --inversion`
  calibration::InversionMethod inversion = calibration::InversionMethod::ls;
  calibration::Outside outside = calibration::kDefaultOutside;  ///< as `correct --outside`
  double step_m = 0.001;  ///< lut: reading step, metres (> 0); default 1 mm
  std::string source;     ///< model file named in the YAML comment
};

/// Readings the model corrects, [first, second] metres: f over the fitted range with keep and
/// drop; the sensor's range window with linear and extrapolate (linear without the sensor's
/// limits: f over the fitted range), or for a model without fitted range. Throws DataError
/// when the model gives neither (no fitted range and no finite range limits).
std::pair<double, double> correctedReadings(const CalibrationModel& model,
                                            calibration::Outside outside,
                                            const std::string& model_file);

/// The ROS parameter YAML (flat keys, to load under the driver's private namespace).
std::string exportYaml(const CalibrationModel& model, const ExportConfig& config);

/// The lookup table: header `reading_m,range_m`, one row per step from the first corrected
/// reading to the last (the last always included); range_m `nan` where `correct` leaves no
/// distance. Throws InputError for a step that is not positive or gives more than 10^7 rows.
std::string exportLut(const CalibrationModel& model, const ExportConfig& config);

}  // namespace lidarcal::pipeline
