// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A calibrated range model and how it was obtained: the content of model.json
// (docs/FORMAT.md). Plain data: calibration/ fills it, io/ reads and writes it.

#include <array>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/pose2.hpp"
#include "common/range_model.hpp"
#include "common/status.hpp"

namespace lidarcal {

/// One row of the order-selection table.
struct OrderRow {
  int order = 0;                   ///< polynomial order n
  std::vector<double> alpha;       ///< coefficients fitted at this order
  double aic = 0.0;                ///< Akaike information criterion (lower is better)
  double bic = 0.0;                ///< Bayesian information criterion (lower is better)
  double validation_mse_m2 = 0.0;  ///< fit on part 1 of 3, error on part 2 (NaN when not computed)
  double test_mse_m2 = 0.0;        ///< fit on part 1 of 3, error on part 3 (NaN when not computed)
  bool invertible = true;          ///< f maps the sensor's reading window to distances one to one
};

/// A landmark as calibrated.
struct CalibratedLandmark {
  int id = 0;                             ///< landmark id
  double x_m = 0.0, y_m = 0.0;            ///< centre, world (commanded) frame
  double radius_m = 0.0;                  ///< radius
  std::array<double, 4> covariance_m2{};  ///< row-major 2x2 covariance of (x, y)
  int stops = 0;                          ///< stops that saw it
  std::string status = "ok";              ///< ok or why it was not used
  bool ok() const { return status == "ok"; }
};

/// Results of the noise-law estimators, reported side by side.
struct NoiseFits {
  /// sigma(d) = |sum beta_i d^i|, ML (Alhashimi et al. 2021 eq. 3)
  std::vector<double> alhashimi2021_beta;
  /// Alhashimi et al. 2016 closed form eqs. 21-26: alpha
  std::vector<double> alhashimi2016_cf_alpha;
  double alhashimi2016_cf_sigma_e = 0.0;       ///< and sigma_e
  std::vector<double> alhashimi2016_ml_alpha;  ///< Alhashimi et al. 2016 full ML eqs. 18-20: alpha
  double alhashimi2016_ml_sigma_e = 0.0;       ///< and sigma_e
  std::array<double, 4> exponent_loglik{};     ///< Alhashimi et al. 2016 eq. 15 for H0..H3
  int exponent_best = -1;                      ///< argmax of the above; -1 when not testable
  std::size_t exponent_batches = 0;            ///< constant-distance batches used
  /// Estimators that could not run on these data, by name ("alhashimi2021_beta",
  /// "alhashimi2016_closed_form", "alhashimi2016_ml", "exponent_test") -> why. They are
  /// informational: the calibration stands without them.
  std::map<std::string, std::string> unavailable;
};

/// Discrepancy::note of a model without a discrepancy estimate.
inline constexpr const char* kDiscrepancyNotEstimated =
    "not estimated (no measured distances beside the fit): the intervals are the fitted curve's "
    "alone. They do not "
    "include how far the sensor may lie from any polynomial between the distances it was fitted at "
    "(model "
    "discrepancy), nor, for a self-calibration, an odometry scale error, which self-calibration "
    "cannot see; "
    "calibrate --reference with ten or more measured distances estimates the first, a few taped "
    "stops remove the second";

/// Model discrepancy (Kennedy & O'Hagan 2001): how far the sensor's mean reading at a distance
/// the fit did not see may lie from the fitted polynomial, beyond the polynomial's own
/// uncertainty (alpha_covariance). Treated as a Gaussian term of standard deviation sigma_m,
/// independent between distances; the predictive standard error of f at d is
/// sqrt(curve SE(d)^2 + sigma_m^2), with Student-t quantiles of `dof` degrees of freedom.
/// Estimated only where measured distances give independent units (calibrate --reference);
/// elsewhere method is "none" and the predictive interval is the curve's (docs/FORMAT.md).
struct Discrepancy {
  /// How sigma_m was estimated: "reml" (restricted maximum likelihood over the measured
  /// entries, calibration/discrepancy.hpp) or "none" (not estimated: sigma_m NaN).
  std::string method = "none";
  /// standard deviation, metres of reading; NaN when none
  double sigma_m = std::numeric_limits<double>::quiet_NaN();
  int dof = 0;  ///< degrees of freedom of its estimate: entries - coefficients; 0 when none
  std::size_t entries = 0;  ///< measured distances (targets at stops) it was estimated from
  /// RMS of the tape errors the entries state (REF.json sigma_m), metres: taken out of sigma_m,
  /// which describes the sensor, not the tape. NaN when none.
  double tape_sigma_m = std::numeric_limits<double>::quiet_NaN();
  /// What the intervals include and do not, in words.
  std::string note = kDiscrepancyNotEstimated;
  /// Whether sigma_m was estimated (and may be used).
  bool estimated() const { return method != "none" && sigma_m >= 0.0; }
};

/// What the plausibility checks found (calibration/plausibility.hpp): each flag false where a
/// warning was added. Kept in memory for code that must decide on a model (the field watcher's
/// switch); model.json carries the warnings' text instead.
struct Plausibility {
  bool correction_supported = true;  ///< the correction exceeds two standard errors somewhere
  bool offset_determined = true;     ///< the offset does not trade off against the pole radius
  bool landmarks_located = true;     ///< the landmark centres are pinned down by the data
  bool correction_plausible = true;  ///< no correction beyond what lidars are built to
  /// None of the checks that say the model may be wrong failed (an unsupported correction is
  /// not wrong, only not shown to help).
  bool trustworthy() const {
    return offset_determined && landmarks_located && correction_plausible;
  }
};

struct CalibrationModel {
  std::string format = "lidarcal-model/1";
  std::string method;            ///< closed-form, joint, oracle or oracle-commanded
  std::string sensor_name;       ///< from sequence.json, when known
  std::optional<int> beams;      ///< beams per scan of the calibrated sensor, when known
  RangeModel model;              ///< bias f, noise law, range window [range_min_m, range_max_m]
  double sigma_theta_rad = 0.0;  ///< bearing noise estimate
  std::string order_rule;        ///< how the order was chosen
  int order_aic = -1, order_validation = -1;  ///< orders each rule picks
  std::vector<OrderRow> orders;               ///< the order-selection table
  NoiseFits noise_fits;                       ///< all noise estimators
  std::vector<CalibratedLandmark> landmarks;  ///< landmark map
  std::vector<Pose2> stop_poses;  ///< pose of each stop: refined (joint) or commanded (closed form)
  std::vector<double> alpha_covariance;  ///< row-major (n+1)x(n+1), empty when not computed
  /// True distances the fit saw, [min, max] metres. The model says nothing outside: `correct`
  /// leaves readings beyond f(min)..f(max) as they are unless told otherwise. Unset (models
  /// written before it was recorded): the whole range window.
  std::optional<std::pair<double, double>> fitted_range_m;
  /// Model discrepancy beside alpha_covariance: together they give the predictive interval.
  Discrepancy discrepancy;
  /// What a user should read before trusting the model (plausibility checks); empty when none.
  std::vector<std::string> warnings;
  /// The plausibility checks' findings behind those warnings (not written to model.json).
  Plausibility plausibility;
  /// Effect terms the joint refinement estimated with them (`calibrate --effects`, name with
  /// unit -> value, e.g. "range_drift_m_per_scan"); empty without effects. They describe the
  /// calibration data; `correct` applies the bias only.
  std::map<std::string, double> effects;
  // Diagnostics
  /// ok, or why there is no usable model (model.json diagnostics.status), with a message a user
  /// can act on (also when ok: a note such as an unsettled noise model).
  Status status;
  int iterations = 0;           ///< solver iterations
  double residual_rms_m = 0.0;  ///< RMS of range residuals
  std::size_t readings = 0;     ///< readings used
  double pose_scatter_m = 0.0;  ///< joint: refined vs commanded stop positions (RMS per coordinate)
  /// joint: odometry between consecutive stops was a prior (continuous motion)
  bool motion_prior = false;
  double heading_scatter_rad = 0.0;  ///< joint: refined vs commanded headings (RMS)
  /// joint with the radius estimated: correlation of alpha_0 with the pole radius (NaN otherwise);
  /// near +-1 the offset is not determined by the data.
  double offset_radius_correlation = std::numeric_limits<double>::quiet_NaN();
};

/// The landmarks the model located (status ok), by id: those it set aside have no circle.
inline std::map<int, const CalibratedLandmark*> locatedLandmarks(const CalibrationModel& m) {
  std::map<int, const CalibratedLandmark*> out;
  for (const CalibratedLandmark& l : m.landmarks)
    if (l.ok()) out[l.id] = &l;
  return out;
}

}  // namespace lidarcal
