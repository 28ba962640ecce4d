// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One check of the model in use against the poles of a stretch of driving. The stretch's
// readings are corrected with the model (only those it was fitted to correct), and the corrected
// readings are calibrated like any drive: poses, pole centres, the radius and a line
// g(d) = a_0 + a_1 d in one maximum-likelihood fit (the joint refinement with the motion prior,
// calibration/joint_refinement.hpp). If the sensor still matches the model, the corrected
// readings are unbiased apart from the model's own error, so the shift s(d) = g(d) - d at the two
// reference distances d_1 < d_2 (the quartiles of the model's fitted range) stays where it was:
// a bump moves a_0, a new scale a_1. The check states s and the fit's covariance of it,
// A Sigma_a A^T with A = [1 d_1; 1 d_2], Sigma_a scaled by N / (N - P): the noise the fit
// estimates from N readings with P parameters (a pose per scan among them) is the
// residuals' mean square, which P parameters shrink. The fit may also carry a bias of its own
// at the stretch's geometry (thin poles seen by a few beams: radius, centre and offset trade
// off). With bias_replicas = R > 0 it is estimated by a parametric bootstrap: the stretch's
// readings are drawn R times from the fitted poses, poles, line and noise law, each replica is
// fitted the same way, and the mean of the replicas' shifts minus the fitted shift is the bias
// (Efron & Tibshirani 1993, ch. 10). The check states s and that bias; unbiasedShift() is s
// minus the bias, with the covariance times (1 + 1/R) for the replicas' own scatter.
// shift_history.hpp decides on it.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <Eigen/Core>

#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"
#include "common/status.hpp"
#include "watch/shift_history.hpp"

namespace lidarcal::watch {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The shift of the corrected readings over one stretch.
struct ModelCheck {
  /// ok, or why the stretch cannot check the model (no readings the model corrects, a fit the
  /// data do not support: calibrate's own refusals).
  Status status{StatusCode::not_run, ""};
  std::array<double, 2> distance_m{kNaN, kNaN};  ///< d_1, d_2, metres
  /// s(d): mean corrected reading minus true distance there, as fitted, metres
  std::array<double, 2> shift_m{kNaN, kNaN};
  /// the fit's standard error of s(d), metres
  std::array<double, 2> shift_se_m{kNaN, kNaN};
  /// the fit's own bias at d, estimated by the replicas (0 without), metres
  std::array<double, 2> fit_bias_m{0.0, 0.0};
  int bias_replicas = 0;                                 ///< replicas that estimated it (0: none)
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< the fit's covariance of s, m^2
  std::pair<double, double> fitted_m{kNaN, kNaN};  ///< distances the stretch's fit saw, metres
  std::size_t poles = 0;                           ///< poles in the fit
  std::size_t readings = 0;                        ///< corrected readings in the fit
  std::size_t scans = 0;                           ///< scans of the stretch
};

/// The shift as fitted, with the fit's covariance.
Shift fittedShift(const ModelCheck& check);
/// The shift less the fit's own bias, with the covariance times (1 + 1/R) for the replicas'
/// scatter; the fitted shift when no replica ran.
Shift unbiasedShift(const ModelCheck& check);

/// How the check fits.
struct CheckFit {
  int threads = 1;  ///< threads of the fit (the result does not depend on it)
  /// Replicas that estimate the fit's own bias (header); 0: none.
  int bias_replicas = 0;
  /// Seed of the replicas (the stretch's first scan: the same stretch draws the same replicas).
  std::uint64_t seed = 0;
};

/// The reference distances of a model: the quartiles of its fitted range (of its reporting
/// window when it records none), metres.
std::array<double, 2> referenceDistances(const CalibrationModel& model);

/// Covariance of the model's own error in corrected distance at the distances: its curve's
/// (alpha_covariance through f'(d)) and its discrepancy's when estimated, m^2.
Eigen::Matrix2d modelShiftCovariance(const CalibrationModel& model,
                                     const std::array<double, 2>& distances_m);

/// Checks `model` against the raw observations of a stretch at the reference distances.
ModelCheck checkModel(const LandmarkObservations& raw, const CalibrationModel& model,
                      const std::array<double, 2>& distances_m, const CheckFit& fit = {});

/// The raw observations corrected with the model: each reading it corrects inside its fitted
/// range moved to the corrected distance; the others dropped, and sightings left without
/// readings dropped.
LandmarkObservations correctedObservations(const LandmarkObservations& raw,
                                           const CalibrationModel& model);

/// A replica of `obs` under its fit: every beam of every sighting of a pole the fit located,
/// read from the fitted pose of its scan along its beam to the fitted circle, through the
/// fitted bias curve with the fitted noise law's Gaussian noise; the commanded poses as
/// recorded. Deterministic in `seed`.
LandmarkObservations replicaObservations(const LandmarkObservations& obs,
                                         const CalibrationModel& fit, std::uint64_t seed);

}  // namespace lidarcal::watch
