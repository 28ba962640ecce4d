// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A simulated scene's own sensor as a calibrated model: the model a check or a correction is held
// against when the truth is known (the watcher's tests and benches, the node's tests).

#include "common/calibration_model.hpp"
#include "common/scene.hpp"

namespace lidarcal::simulation {

/// The scene's range model as a model.json would carry it: method "truth", status ok, fitted over
/// the distances from its path (seed 1) to the poles' surfaces (poleDistanceRange, as a
/// calibration of the drive would report), alpha_covariance all zero (the truth has no standard
/// error).
CalibrationModel truthModel(const Scene& scene);

}  // namespace lidarcal::simulation
