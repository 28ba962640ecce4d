// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The predictive check of calibration/predictive_check.hpp as `evaluate` writes and prints it.

#include <string>

#include <nlohmann/json.hpp>

#include "calibration/predictive_check.hpp"

namespace lidarcal::pipeline {

/// E.json's `predictive` block (docs/FORMAT.md, "Evaluation against reference measurements").
nlohmann::ordered_json predictiveJson(const calibration::PredictiveCheck& check);

/// A Markdown table of the entries with their intervals, and a line with the counts.
std::string predictiveTable(const calibration::PredictiveCheck& check);

}  // namespace lidarcal::pipeline
