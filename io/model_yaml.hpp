// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The range model as `lidarcal export --format yaml` writes it (format "lidarcal-ros-params/1",
// docs/FORMAT.md), read back for the live nodes: a ROS user keeps one YAML file per sensor and
// points the node's `model` parameter at it, as at a model.json. The YAML also carries the
// inversion and outside policy it was exported with; the nodes use them unless their own
// parameters say otherwise.
//
// Reads the flat `key: value  # comment` lines that export writes (numbers, [a, b] lists, JSON
// strings). Read back, the model corrects every reading exactly as the model.json it was
// exported from (the numbers are written to read back as the same doubles), provided that
// model.json recorded its fitted range.

#include <filesystem>
#include <string>

#include "common/calibration_model.hpp"

namespace lidarcal::io {

/// A model read from the YAML of `lidarcal export --format yaml`.
struct ExportedModel {
  CalibrationModel model;  ///< sensor, bias, fitted range (valid_range_m), range limits, noise law
  std::string inversion;   ///< `inversion` as exported: ls or ml
  std::string outside;     ///< `outside` as exported: a policy name of `correct --outside`
};

/// True when `file` starts like the YAML of export (its text holds `format:
/// "lidarcal-ros-params/1"` before any `{`), false for anything else (e.g. model.json). Throws
/// InputError when it cannot be read.
bool isExportedModelYaml(const std::filesystem::path& file);

/// Reads the YAML. Throws InputError naming the key for a missing or malformed entry.
ExportedModel readExportedModelYaml(const std::filesystem::path& file);

}  // namespace lidarcal::io
