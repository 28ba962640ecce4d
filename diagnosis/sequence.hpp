// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Diagnosis of a scan sequence with landmarks (diagnosis/diagnosis.hpp), on what calibration
// consumes: the beams of every landmark sighting.
//   baseline   calibrate() (joint refinement, order by its rule) with every heading held at the
//              commanded one and the squared noise law of Alhashimi et al. 2016; then one
//              refinement on every beam of every sighting (the fixed reading set all models are
//              compared on);
//   replicas   simulateLandmarkLevel() from the fitted poses, centres, radius, bias and noise,
//              keeping the (scan, landmark) pairs of the data, refitted from the baseline;
//   candidates refineJoint() with one effect term on (JointEffects), from the baseline;
//   held out   folds by scan position within each stop (each stop keeps scans in every fold,
//              so its pose is estimated from the other scans); with one scan per stop, folds by
//              (stop + landmark);
//   identifiability: information on the effect left after the nuisance parameters (bias,
//              radius, centres, stop positions with their priors), from the model's Jacobian.

#include <vector>

#include "common/landmark_observations.hpp"
#include "diagnosis/diagnosis.hpp"

namespace lidarcal::diagnosis {

/// Diagnoses. `true_range_m` (optional, aligned with obs.sightings[i].beams[j]) gives the
/// calibration gain against the truth. Returns a status instead of throwing for data that
/// cannot be diagnosed (no landmark, too few readings).
DiagnosisResult diagnoseSequence(const LandmarkObservations& obs, const DiagnoseConfig& config,
                                 const std::vector<std::vector<double>>* true_range_m = nullptr);

}  // namespace lidarcal::diagnosis
