// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The oracle of Alhashimi et al. 2016: the range model fitted against known distances, the best
// any self-calibration of these readings could do. Used against a simulator's truth only.

#include <vector>

#include "calibration/calibration_config.hpp"
#include "calibration/range_model_fit.hpp"
#include "common/calibration_model.hpp"

namespace lidarcal::calibration {

/// The same fits as calibrate() against known distances (pairs' d_m are true): with the squared
/// noise law, full ML of model (1) for every order (eqs. 18-20, from the closed form eqs. 21-26)
/// and the order by AIC on that likelihood; else the closed form's least squares.
/// `batches` (optional) feed the noise-exponent test; orders that cannot be inverted over the
/// reading window [range_min_m, range_max_m] are not chosen (no check with the defaults).
CalibrationModel calibrateAgainstTruth(const std::vector<RangePair>& pairs,
                                       const CalibrationConfig& config,
                                       const std::vector<std::vector<double>>& batches = {},
                                       double range_min_m = 0.0, double range_max_m = 1e9);

}  // namespace lidarcal::calibration
