// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Calibration without ground truth, end to end on landmark observations (calibrate.cpp reads
// as these stages, each in its own file):
//   1. triangulate every landmark from its bearings (Alhashimi et al. 2021 section 3.1;
//      triangulation.hpp),
//   2. the closed-form seed: distances from the landmarks to the stops, the bias polynomial for
//      orders 0..n_max and the order by AIC or held-out validation (section 3.2), the noise law
//      (closed_form_stage.hpp),
//   3. (method joint) refine poses, landmarks, radius and bias together from every reading
//      (joint_stage.hpp),
//   4. the side estimators: Alhashimi et al. 2021's and 2016's noise fits and the 2016
//      noise-exponent test (noise_fits.hpp),
//   5. plausibility warnings (plausibility.hpp); the refusals of each stage are in refusals.hpp.
// And the oracle: the same fits against true distances (oracle.hpp).

#include "calibration/calibration_config.hpp"
#include "calibration/closed_form_stage.hpp"
#include "calibration/joint_refinement.hpp"
#include "calibration/oracle.hpp"
#include "calibration/plausibility.hpp"
#include "calibration/range_model_fit.hpp"
#include "calibration/refusals.hpp"
#include "calibration/triangulation.hpp"
#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"

namespace lidarcal::calibration {

/// Calibrates. The result's status is "ok" or says why the data cannot support a model.
CalibrationModel calibrate(const LandmarkObservations& obs, const CalibrationConfig& config);

}  // namespace lidarcal::calibration
