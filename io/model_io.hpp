// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// model.json: a calibrated range model (docs/FORMAT.md).

#include <filesystem>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "common/calibration_model.hpp"

namespace lidarcal::io {

/// Writes model.json atomically.
void writeModel(const std::filesystem::path& file, const CalibrationModel& model);
/// Reads and validates model.json. Throws InputError naming the field.
CalibrationModel readModel(const std::filesystem::path& file);
/// model.json's content (what writeModel writes), e.g. for one sensor's block of a rig model.
nlohmann::ordered_json modelJson(const CalibrationModel& model);
/// A model from its JSON; errors name `file` and the field under `path` (e.g. "sensors[1].model").
CalibrationModel modelFromJson(const nlohmann::json& j, const std::string& file,
                               const std::string& path = {});

}  // namespace lidarcal::io
