// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The range model (method "reference") from wall-to-wall spans and tape distances: the fits of
// span_fit.hpp for every order the entries determine, the order by leave-one-group-out
// cross-validation (a group: the spans between one pair of walls, or one tape distance; the
// rule calibrateWithReference applies over the stops, reference.hpp), and the noise law from
// the readings at the distances the chosen fit gives the walls (Alhashimi et al. 2016's exponent
// test, eqs. 10-15).

#include <cstddef>
#include <string>
#include <vector>

#include "calibration/calibrate.hpp"
#include "calibration/reference.hpp"
#include "calibration/span_fit.hpp"
#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"

namespace lidarcal::calibration {

/// How one entry is reproduced: uncorrected, by the chosen model, and by the chosen order fitted
/// without the entry's group (the check on walls the fit did not see).
struct SpanCheck {
  std::string entry;         ///< "spans[k]" or "distances[k]"
  std::size_t stop = 0;      ///< its stop
  double reference_m = 0.0;  ///< what was measured, metres
  /// what the uncorrected sensor says (f(d) = d) - what was measured, metres
  double raw_error_m = 0.0;
  double fitted_error_m = 0.0;  ///< with the chosen model, metres
  /// With the chosen order fitted without this entry's group (every span between the same two
  /// walls), metres; NaN when the other entries do not determine it.
  double left_out_error_m = 0.0;
};

/// The model from `problem` (spans and tape distances; `tape` their readings) and the walls'
/// readings in `obs`. Orders 0 (the offset f(d) = d + alpha_0) to config.max_order are fitted;
/// candidates are those the entries determine, whose leave-one-group-out fits the other groups
/// determine too (with a single group: the offset, without cross-validation), and that increase
/// over the fitted distances; the one with the smallest leave-one-group-out mean squared error
/// wins. `checks` (optional) receives one row per entry; `readings` (optional) the readings the
/// noise law was fitted on: every reading of the walls' beams at the distance the chosen model
/// places it (walls numbered after the tape entries), then `tape`.
CalibrationModel calibrateWithSpans(const LandmarkObservations& obs, const SpanProblem& problem,
                                    const std::vector<KnownReading>& tape,
                                    const CalibrationConfig& config,
                                    std::vector<SpanCheck>* checks = nullptr,
                                    std::vector<KnownReading>* readings = nullptr);

}  // namespace lidarcal::calibration
