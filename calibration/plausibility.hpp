// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What a user should know before trusting a calibrated model: warnings appended to its
// `warnings`, never a refusal (calibrate() and the reference fits call them last).

#include "calibration/joint_refinement.hpp"
#include "common/calibration_model.hpp"

namespace lidarcal::calibration {

/// Corrections beyond this fraction of the distance (at 0.5 m or more) inside the fitted range
/// draw a warning.
inline constexpr double kImplausibleCorrection = 0.25;

/// The largest correction |f(d) - d| over max(d, 0.5 m) for d in [lo, hi] (51 points), and
/// where it is: beyond kImplausibleCorrection it is more than lidars are built to.
struct RelativeCorrection {
  double fraction = 0.0;  ///< |f(d) - d| / max(d, 0.5 m)
  double at_m = 0.0;      ///< the distance d where it is largest, metres
  double mm = 0.0;        ///< |f(d) - d| there, millimetres
};
RelativeCorrection largestRelativeCorrection(const BiasPolynomial& bias, double lo, double hi);

/// A median standard error of the landmark centres above this, metres, draws a warning.
inline constexpr double kUnlocatedLandmarkM = 0.1;

/// What a user should know before trusting a self-calibrated model, appended to m.warnings:
/// an offset whose correlation with the estimated pole radius exceeds 0.9 in magnitude (from
/// `j`, which may be null; sets m.offset_radius_correlation), landmark centres whose median
/// standard error (largest axis, from `j`) exceeds kUnlocatedLandmarkM, and corrections
/// |f(d) - d| above kImplausibleCorrection of max(d, 0.5 m) inside m.fitted_range_m.
void addPlausibilityWarnings(CalibrationModel& m, const JointResult* j);

/// Appends a warning to m.warnings when the correction is nowhere distinguishable from none:
/// |f(d) - d| within two standard errors of f(d) everywhere in m.fitted_range_m (applying it
/// may add as much error as it removes). Needs the covariance and the fitted range; appended
/// also by addPlausibilityWarnings.
void addUnsupportedCorrectionWarning(CalibrationModel& m);

}  // namespace lidarcal::calibration
