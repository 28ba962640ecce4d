// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The noise law of a fitted bias, and the noise estimators reported beside it (model.json
// "noise_fits"): Alhashimi et al. 2021's noise polynomial, Alhashimi et al. 2016's closed form
// and ML (eqs. 18-26) and its noise-exponent test (section 4).

#include <vector>

#include "common/calibration_model.hpp"
#include "common/range_model.hpp"

namespace lidarcal::calibration {

/// Noise parameters of the law `kind` for the bias f, from the (distance d, reading y) pairs:
/// squared, sigma_e^2 = mean of r^2 / f(d)^4; constant, sigma_e^2 = mean of r^2; polynomial, fitted
/// to |r| at `order` (at least 0); r = y - f(d). Throws std::invalid_argument for another law.
NoiseModel fitNoiseLaw(NoiseKind kind, int order, const BiasPolynomial& f,
                       const std::vector<double>& d, const std::vector<double>& y);

/// Fills m.noise_fits with the estimators side by side on the pairs (d, y) and the bias
/// m.model.bias (order `order`, at least 1 for the fits), `batches` of readings at constant
/// distance feeding the exponent test. Two independent groups run on up to `threads` threads
/// (0: automatic); an estimator that fails on degenerate data is noted in
/// NoiseFits::unavailable, never thrown: the calibration does not depend on it.
void fillNoiseFits(CalibrationModel& m, int order, const std::vector<double>& d,
                   const std::vector<double>& y, const std::vector<std::vector<double>>& batches,
                   int threads);

}  // namespace lidarcal::calibration
