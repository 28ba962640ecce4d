// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The JSON of an evaluation against the truth, shared by `lidarcal evaluate` (cmd_evaluate.cpp,
// where it is defined) and `lidarcal run`'s summary.

#include <nlohmann/json.hpp>

#include "calibration/truth_evaluation.hpp"

namespace lidarcal::pipeline {

/// Scans, lost returns and the MSE comparisons (landmarks, walls, all returns, and the returns
/// beyond the fitted range) of `e`.
nlohmann::ordered_json evaluationJson(const calibration::Evaluation& e);

}  // namespace lidarcal::pipeline
