// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The joint refinement (calibration/joint_refinement.hpp) as the sequence diagnosis drives it:
// the baseline's setup, one effect term switched on, starts from earlier solutions, warm refits.
// Internal to the diagnosis library (diagnosis/sequence/).

#include "calibration/calibrate.hpp"
#include "calibration/joint_refinement.hpp"
#include "common/landmark_observations.hpp"
#include "diagnosis/diagnosis.hpp"

namespace lidarcal::diagnosis::sequence {
// The sequence diagnosis refits with the calibration stages (joint refinement, range model,
// inversion).
using namespace lidarcal::calibration;

/// The refinement `c` with effect e's term switched on; throws std::invalid_argument when e has
/// none.
JointConfig effectConfig(JointConfig c, Effect e);

/// Fits that start from a converged solution (replicas, folds) skip the geometry pass and
/// re-estimate the noise law at most twice.
JointConfig warmStartConfig(JointConfig c);

/// Negative log-likelihood of the readings and the odometry (infinite for a failed fit).
double totalNegLogLikelihood(const JointResult& r);

/// The start `i` with its bias polynomial cut or padded with zeros to `order`.
JointInit withOrder(JointInit i, int order);

/// The baseline's joint refinement: the published model (Alhashimi et al. 2021 eq. 8, Alhashimi et
/// al. 2016 eq. 1 with the squared noise law) on every beam of every sighting; the headings held at
/// the commanded ones, except on a continuous recording, where the motion prior refines them.
JointConfig baselineConfig(const CalibrationModel& cal, const CalibrationConfig& cc,
                           const LandmarkObservations& obs, const DiagnoseConfig& config);

}  // namespace lidarcal::diagnosis::sequence
