// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Learning a new model on the robot, and when to switch to it. A refit calibrates the raw
// readings of the stretch since the alarm as `calibrate` would (the joint refinement, its order
// chosen by the parsimonious AIC). The watcher switches only when all three hold:
//   differs     the sensor differs from the model in use since the alarm: the checks made
//               after the alarm's stretch have another mean than those before it
//               (shift_history.hpp, the same-mean test; against zero when the model was wrong
//               from the start), p below the level the engine gives this refit (switch_level
//               spent over the refits that follow one alarm). Checks are fits of one kind over
//               stretches of one length, so their own bias and the scale of their covariance
//               cancel, as in the alarm's test; a Wald test of the candidate's curve against the
//               model's (calibration/model_comparison.hpp) takes both as stated, and on clean
//               drives among thin poles it rejected a correct model far more often than its
//               level;
//   determined  its curve's standard error stays below max_standard_error_m over the distances
//               both models were fitted at, and its
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
#include "watch/shift_history.hpp"
#include "watch/watch_settings.hpp"

namespace lidarcal::watch {

/// The test that the sensor differs from the model in use since the alarm.
struct SwitchTest {
  bool tested = false;     ///< enough checks since the alarm to test
  FTest f;                 ///< the test (shift_history.hpp)
  std::size_t checks = 0;  ///< checks since the alarm it used
  std::string why_not;     ///< when not tested: why
};

/// What a candidate model was judged to be.
struct SwitchDecision {
  bool differs = false;     ///< (with a model in use) the sensor differs from it significantly
  SwitchTest test;          ///< the test behind `differs`
  bool determined = false;  ///< its standard error is small enough (header)
  bool plausible = false;   ///< calibrate's plausibility checks pass
  bool adopt = false;       ///< all three (or, with no model in use, the last two)
  /// Candidate minus model in use over the distances both were fitted at (empty with none):
  /// what the switch changes, and the model in use's error as the data now show it.
  calibration::ModelDifference difference;
  double largest_se_m = 0.0;  ///< the candidate's largest curve standard error compared, metres
  std::string reason;         ///< the decision in words
};

/// Judges `candidate` (a refit) against the model in use (null: none), with the test that the
/// sensor differs from the model in use (ignored with none).
SwitchDecision decideSwitch(const CalibrationModel& candidate, const CalibrationModel* in_use,
                            const SwitchTest& test, const LearnSettings& settings);

/// Calibrates the raw observations of a stretch as `calibrate` does for a drive (joint
/// refinement, orders up to settings.max_order, the motion prior).
CalibrationModel refitModel(const LandmarkObservations& raw, const LearnSettings& settings,
                            int threads);

/// `count` distances evenly over [lo, hi], metres.
std::vector<double> evenDistances(double lo, double hi, int count);

}  // namespace lidarcal::watch
