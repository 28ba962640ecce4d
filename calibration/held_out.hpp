// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A model checked on measured entries it was not fitted on, at the level of the readings (the
// simulated counterpart of `evaluate --reference --model` on recordings the fit never saw; used
// by the tests and bench/predictive_coverage.cpp). Each held-out entry gives the weighted mean
// residual of its readings about the model's f at their measured distances, with the variances
// the model says describe it (calibration/discrepancy.hpp):
//   the curve's, SE_curve(d)^2 (alpha_covariance);
//   the discrepancy's, sigma_delta^2 (model.json discrepancy);
//   the entry's own: its readings' noise averaged over the entry, and its stated tape error
//   through the slope, (f'(d) sigma_tape)^2.

#include <cstddef>
#include <string>
#include <vector>

#include "calibration/reference.hpp"
#include "common/calibration_model.hpp"

namespace lidarcal::calibration {

/// Standard error of f(d) from the model's alpha_covariance, metres of reading; NaN without it.
double curveStandardError(const CalibrationModel& model, double d_m);

/// The exponent k of the model's noise law sigma = sigma_e f(d)^k (0 constant, 2 squared, the
/// exponent of a power law; 0 for any other law, whose weights are then equal).
double noiseLawExponent(const NoiseModel& noise);

/// One held-out entry about a model.
struct HeldOutEntry {
  std::size_t entry = 0;    ///< the entry's label (KnownReading::entry)
  double distance_m = 0.0;  ///< weighted mean measured distance of its readings, metres
  double residual_m = 0.0;  ///< weighted mean of reading - f(distance), metres
  double curve_se_m = 0.0;  ///< SE_curve at distance_m, metres
  /// sqrt(SE_curve^2 + sigma_delta^2), metres (the curve's alone without a discrepancy)
  double predictive_se_m = 0.0;
  /// the entry's own: sqrt(noise of the mean + (f' sigma_tape)^2), metres
  double entry_se_m = 0.0;
  /// Whether |residual| <= t sqrt(predictive_se^2 + entry_se^2), t the half-width factor of the
  /// central interval of probability `level` (predictiveFactor, the entry's own variance known).
  bool inside(const Discrepancy& discrepancy, double level) const;
};

/// The held-out entries of `readings` (the readings of entries the model was not fitted on;
/// their d_m from the measured distances) about `model`, in ascending entry order.
std::vector<HeldOutEntry> heldOutEntries(const CalibrationModel& model,
                                         const std::vector<KnownReading>& readings);

/// The model discrepancy of `model` over measured entries that were terms of its fit beside
/// other data (the self-calibration's likelihood, `--reference-fit combined`): REML over the
/// entries' residuals about f, as calibrateWithReference does over its own (the polynomial's
/// coefficients counted as fitted to them, which leaves entries - coefficients degrees of
/// freedom). Method "none", with a note saying why, when the entries cannot leave one.
Discrepancy discrepancyOfMeasuredEntries(const CalibrationModel& model,
                                         const std::vector<KnownReading>& readings);

/// One warning for each measured entry that disagrees with the others beyond chance: its
/// studentized deleted residual (deletedResiduals, about the model's f at its order) has a
/// Bonferroni-adjusted p-value, min(1, entries x p), below `alpha`. A wrong stop number or
/// tape reading otherwise passes as model discrepancy and widens every predictive interval.
/// Each names the entry as distances[k] with its stop; empty when none disagrees.
std::vector<std::string> disagreeingEntryWarnings(const CalibrationModel& model,
                                                  const std::vector<KnownReading>& readings,
                                                  double alpha = 0.05);

/// A fit on some stops and the others about it.
struct HalfCheck {
  /// calibrateWithReference on the fitted stops (its status says whether it is usable)
  CalibrationModel model;
  /// the other stops' entries about it (empty when the fit failed)
  std::vector<HeldOutEntry> held_out;
};

/// Interleaved halves: the model fitted to the readings of the stops with stop % 2 ==
/// fit_parity (0 or 1), and the other stops' entries about it.
HalfCheck checkInterleavedHalf(const std::vector<KnownReading>& readings, int fit_parity,
                               const CalibrationConfig& config = {});

}  // namespace lidarcal::calibration
