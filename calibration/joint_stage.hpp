// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Stage 3 of calibrate(): the joint refinement (joint_refinement.hpp) from the closed form.
// Pass 1 settles the geometry at order 2; pass 2 fits every order from there on one fixed set
// of readings (so their likelihoods compare the same data) and picks one by the rule; the
// covariance is computed at the chosen order.

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calibration/calibration_config.hpp"
#include "calibration/closed_form_stage.hpp"
#include "calibration/joint_refinement.hpp"
#include "common/calibration_model.hpp"

namespace lidarcal::calibration {

/// The joint refinement's result at the chosen order, the order table and the AIC's choice.
struct JointStage {
  JointResult result;          ///< the fit at the chosen order (its status says whether it ran)
  std::vector<OrderRow> rows;  ///< one row per order 1..max_order (empty when pass 1 failed)
  std::size_t best_aic = 0;    ///< index (order - 1) of the smallest admissible AIC
};

/// Runs both passes from the closed form (`seed`, and `closed_form_model` its model) with the
/// landmarks `tri` of radius `radius_m`; reports progress through config.progress.
JointStage jointStage(const LandmarkObservations& obs, const CalibrationConfig& config,
                      const std::vector<LandmarkEstimate>& tri, const ClosedFormSeed& seed,
                      double radius_m, const RangeModel& closed_form_model);

/// Starting centres for the joint refinement: bearing-only triangulation places far landmarks
/// poorly along the line of sight, so start each triangulated landmark at the mean of
/// commanded stop + (f^-1(central reading) + radius) along the bearing, with the closed-form f
/// (the triangulated centre when no reading inverts).
std::map<int, Eigen::Vector2d> rangeBearingCentres(const LandmarkObservations& obs,
                                                   const std::vector<LandmarkEstimate>& tri,
                                                   const RangeModel& model, double radius);

/// The estimated effect terms that were switched on, by name (model.json "effects").
std::map<std::string, double> effectValues(const JointEffects& on, const JointEffectEstimates& e);

/// The joint refinement into the model: order table and rule, bias, noise law, poses, landmark
/// centres with their covariance, effect terms, diagnostics and fitted range; a fit that did not
/// converge is usable, and its status message says so.
void fillJoint(CalibrationModel& m, const JointStage& js, const CalibrationConfig& config);

}  // namespace lidarcal::calibration
