// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Why calibrate() cannot give a model from these observations: each refusal sets the model's
// status (code and a message naming what to record or which option to give).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "calibration/calibration_config.hpp"
#include "calibration/joint_refinement.hpp"
#include "calibration/triangulation.hpp"
#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"

namespace lidarcal::calibration {

/// Largest distance between two stop positions (the triangulation baseline), metres; 0 without
/// stops.
double pathExtent(const std::vector<Pose2>& poses);

/// Why stops at these poses cannot triangulate landmarks (they span less than
/// config.min_baseline_m: the sensor turned or stood still), or nothing when they can.
std::optional<std::string> baselineProblem(const std::vector<Pose2>& stops,
                                           const CalibrationConfig& config);

/// Refuses observations no stage can use: stops without a baseline (status no_baseline), or the
/// dark-surface noise term asked for on readings without varying intensities (no_intensity).
/// True when refused.
bool refuseUnusableInput(CalibrationModel& m, const LandmarkObservations& obs,
                         const CalibrationConfig& config);

/// Refuses a triangulation without a usable landmark (no_usable_landmark, the first three
/// landmarks' reasons from m.landmarks) or without a radius (no_radius). True when refused.
bool refuseTriangulation(CalibrationModel& m, const std::vector<LandmarkEstimate>& tri, int usable,
                         double radius_m);

/// Refuses a closed form with fewer than config.max_order + 3 landmark-stop distances
/// (too_few_observations); says so when no reading met its landmark in front of the sensor
/// (the path, pathExtent(obs.commanded), too short). True when refused.
bool refuseTooFewPairs(CalibrationModel& m, const LandmarkObservations& obs,
                       const CalibrationConfig& config, const std::vector<LandmarkEstimate>& tri,
                       std::size_t pairs, int usable);

/// Refuses a joint refinement that failed, or that ran away: a solution placing a landmark where
/// the sensor could not have read it (distances far beyond its range limit), at a stop, or with a
/// bias falling with distance where it saw the landmarks has moved along a direction the data do
/// not pin down (seen with a single landmark: its centre, the bias and the poses trade off).
/// Sets status joint_failed; true when refused.
bool refuseJoint(CalibrationModel& m, const JointResult& j, const LandmarkObservations& obs,
                 int usable, double baseline_m);

}  // namespace lidarcal::calibration
