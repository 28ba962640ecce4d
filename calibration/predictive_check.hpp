// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Each measured distance (`evaluate --reference --model`) checked against the model's two kinds
// of interval. The error checked is what the corrected scans measure minus the measured
// distance; under the model it has mean 0 and variance
//   SE_pred(d)^2 + SE_measured^2 + sigma_tape^2,
// SE_pred the correction's predictive standard error at the entry's distance (the fitted curve
// and the model discrepancy: calibration/discrepancy.hpp; the same rule `correct` writes into
// correction_se), SE_measured the standard error of the scans' mean, sigma_tape the entry's
// stated tape error (REF.json sigma_m). The predictive intervals use Student-t quantiles with
// the discrepancy's degrees of freedom, raised for the share of the variance that is known (the
// scans' and the tape's: Welch-Satterthwaite, predictiveFactor); the curve's
// interval is +-1.96 with the curve's standard error in place of SE_pred (what the model's
// coefficients alone would claim).

#include <cstddef>
#include <string>
#include <vector>

#include "calibration/filtering.hpp"
#include "calibration/reference.hpp"
#include "common/calibration_model.hpp"
#include "common/reference.hpp"

namespace lidarcal::calibration {

/// Probability of the "one standard error" predictive interval: 68.27 %.
inline constexpr double kLevel68 = 0.6827;
/// Probability of the wide predictive interval.
inline constexpr double kLevel95 = 0.95;

/// One reference entry against the intervals.
struct EntryInterval {
  std::size_t entry = 0;     ///< REF.json distances index
  double reference_m = 0.0;  ///< the measured distance, metres
  /// found on the corrected scans, and corrected there (see predictiveCheck)
  bool checked = false;
  double error_m = 0.0;          ///< corrected measured - reference, metres
  double curve_se_m = 0.0;       ///< the correction's curve standard error at the entry, metres
  double predictive_se_m = 0.0;  ///< the correction's predictive standard error there, metres
  double measured_se_m = 0.0;    ///< standard error of the scans' mean (0 when not known), metres
  double tape_sigma_m = 0.0;     ///< the entry's stated tape error, metres
  double interval_se_m = 0.0;    ///< sqrt(predictive^2 + measured^2 + tape^2), metres
  double factor_68 = 0.0;  ///< t_68: half-width of the 68 % predictive interval in interval_se_m
  double factor_95 = 0.0;  ///< t_95: and of the 95 % one
  bool inside_68 = false;  ///< |error| <= t_68 interval_se_m
  bool inside_95 = false;  ///< |error| <= t_95 interval_se_m
  bool inside_curve_95 = false;  ///< |error| <= 1.96 sqrt(curve^2 + measured^2 + tape^2)
};

/// The entries and how many of them each interval holds.
struct PredictiveCheck {
  Discrepancy discrepancy;  ///< the model's
  /// half-width of the 68 % interval of the correction alone, in its predictive SE
  double factor_68 = 0.0;
  /// and of the 95 % one (each entry has its own, with its known variances)
  double factor_95 = 0.0;
  std::vector<EntryInterval> entries;
  /// counts over the checked entries
  std::size_t checked = 0, inside_68 = 0, inside_95 = 0, inside_curve_95 = 0;
};

/// Each entry of `corrected` (matched on scans corrected by `correct`) against the intervals of
/// `model`. An entry is checked when it was found and its readings were corrected: inside the
/// fitted range, or beyond it under an `outside` policy that corrects (linear, extrapolate).
PredictiveCheck predictiveCheck(const std::vector<ReferenceMatch>& corrected, const Reference& ref,
                                const CalibrationModel& model, const ReadingCorrector& correct);

}  // namespace lidarcal::calibration
