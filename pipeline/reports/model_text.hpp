// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A calibrated model in words, for stdout and the report: every coefficient with its standard
// error, the correction at a few distances inside the fitted range (with the curve's standard
// error and the predictive interval beside it),
// the range the model was fitted over, and the plausibility warnings.

#include <string>
#include <vector>

#include "calibration/filtering.hpp"
#include "calibration/reference.hpp"
#include "calibration/span_calibration.hpp"
#include "common/calibration_model.hpp"
#include "common/number_text.hpp"

namespace lidarcal::pipeline {

/// "0.05250 + 0.88380 d + 0.05840 d^2"; with `se` (one per coefficient, NaN to leave one out),
/// each coefficient followed by " (+-SE)".
std::string polynomialText(const std::vector<double>& a, const std::vector<double>& se = {});

/// Standard error of each bias coefficient (NaN when the covariance was not computed).
std::vector<double> coefficientErrors(const CalibrationModel& m);

/// Standard error of f(d) at distance d from the covariance of alpha (NaN without it): the
/// curve's standard error.
double biasError(const CalibrationModel& m, double d_m);

/// Half-width of the central predictive interval of probability `level` of f(d) at a distance
/// the fit did not see: the curve's standard error and the model discrepancy combined, times
/// the Student-t quantile of the discrepancy's degrees of freedom (calibration/discrepancy.hpp;
/// the curve's normal interval when the model has no discrepancy). NaN without covariance.
double predictiveHalfWidth(const CalibrationModel& m, double d_m, double level);

/// The model discrepancy in words: its size, how it was estimated and what the intervals
/// include (or why there is none).
std::string discrepancyText(const CalibrationModel& m);

/// "0.05250 (+-0.00110) + 0.88380 (+-0.00090) d + ..." (no errors when not computed).
std::string polynomialWithErrors(const CalibrationModel& m);

/// Distances at which to show the correction: inside the fitted range (or the sensor window
/// when the fitted range is unknown), about five of them, rounded.
std::vector<double> tableDistances(const CalibrationModel& m);

/// "order 2", or "an offset only (order 0)" for f(d) = d + alpha_0 with alpha_1 held at 1.
std::string orderText(const CalibrationModel& m);

/// Several lines of plain text: method, f with errors, fitted range, noise, corrections at
/// tableDistances() with errors, warnings.
std::string modelSummary(const CalibrationModel& m);

/// What happened to the returns beyond the fitted range, in a sentence (empty when there were
/// none): how many, the share of all returns, their readings' span, and the policy. When most
/// returns lie beyond, a second sentence starting "warning:" says so and what to record.
std::string beyondFitText(const calibration::FilteringStats& stats, const CalibrationModel& m,
                          calibration::Outside outside);

/// The reference distances as matched: stop, target, measured (tape) distance, what the scans
/// read there (mean over the scans, its standard error), the difference, and the readings used
/// (Markdown table). With `corrected`, a second column set for the corrected scans; with
/// `model`, entries outside its fitted range are marked, and left out of the RMS when `outside`
/// leaves their readings uncorrected (keep, drop).
std::string referenceTable(const std::vector<calibration::ReferenceMatch>& raw,
                           const std::vector<calibration::ReferenceMatch>* corrected = nullptr,
                           const CalibrationModel* model = nullptr,
                           calibration::Outside outside = calibration::kDefaultOutside);

/// The spans of a fit (Markdown table): the two walls each was found between (normal direction
/// and distance as read), the measured span, and what the sensor says minus that: uncorrected,
/// with the model, and with the model's order fitted without the entry and the other spans
/// between its walls; then the RMS of each column. Tape distances fitted beside the spans are
/// rows too.
std::string spanTable(const calibration::SpanReadings& found,
                      const std::vector<calibration::SpanCheck>& checks);

/// The spans as measured on the scans (sum of the two walls' line distances, mean over the
/// scans), raw and, with `corrected`, on the corrected scans (Markdown table with the RMS).
std::string spanEvaluationTable(const std::vector<calibration::SpanMatch>& raw,
                                const std::vector<calibration::SpanMatch>* corrected = nullptr);

}  // namespace lidarcal::pipeline
