// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Learning a new model on the robot, and when to switch to it. A refit calibrates the raw
// readings of the stretch since the alarm as `calibrate` would (the joint refinement, its order
// chosen by the parsimonious AIC). The watcher switches only when all three hold:
//   differs     the candidate's bias differs from the model in use's where both were fitted
//               (calibration/model_comparison.hpp: Wald over 11 distances, p below the
//               level the engine gives this refit: switch_level spent over the refits that
//               follow one alarm);
//   determined  its curve's standard error stays below max_standard_error_m there, and its
//               expected squared error, 2 SE_c^2 averaged over those distances, is below the
//               model in use's as the data now show it (the squared difference, which holds the
//               in-use model's error plus the candidate's: E[D^2] = err_in_use^2 + SE_c^2);
//   plausible   it passes calibrate's plausibility checks (common/calibration_model.hpp,
//               Plausibility::trustworthy).
// With no model in use, a candidate is adopted once it is determined over its own fitted range
// and plausible.

#include <string>
#include <vector>

#include "calibration/model_comparison.hpp"
#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"
#include "watch/watch_settings.hpp"

namespace lidarcal::watch {

/// What a candidate model was judged to be.
struct SwitchDecision {
  bool differs = false;     ///< (with a model in use) it differs significantly where both fit
  bool determined = false;  ///< its standard error is small enough (header)
  bool plausible = false;   ///< calibrate's plausibility checks pass
  bool adopt = false;       ///< all three (or, with no model in use, the last two)
  /// Candidate minus model in use over the distances both were fitted at (empty with none).
  calibration::ModelDifference difference;
  double largest_se_m = 0.0;  ///< the candidate's largest curve standard error compared, metres
  std::string reason;         ///< the decision in words
};

/// Judges `candidate` (a refit) against the model in use (null: none).
SwitchDecision decideSwitch(const CalibrationModel& candidate, const CalibrationModel* in_use,
                            const LearnSettings& settings);

/// Calibrates the raw observations of a stretch as `calibrate` does for a drive (joint
/// refinement, orders up to settings.max_order, the motion prior).
CalibrationModel refitModel(const LandmarkObservations& raw, const LearnSettings& settings,
                            int threads);

/// `count` distances evenly over [lo, hi], metres.
std::vector<double> evenDistances(double lo, double hi, int count);

}  // namespace lidarcal::watch
