#pragma once
// model.json: a calibrated range model (docs/FORMAT.md).

#include <filesystem>

#include "common/calibration_model.hpp"

namespace lidarcal::io {

/// Writes model.json atomically.
void writeModel(const std::filesystem::path& file, const CalibrationModel& model);
/// Reads and validates model.json. Throws InputError naming the field.
CalibrationModel readModel(const std::filesystem::path& file);

}  // namespace lidarcal::io
