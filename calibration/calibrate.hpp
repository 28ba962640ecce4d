#pragma once
// Calibration without ground truth, end to end on landmark observations:
//   1. triangulate every landmark from its bearings (seed 000 section 3.1),
//   2. distances from the landmarks to the stops, the bias polynomial for orders 0..n_max and
//      the order by AIC and by held-out validation (seed 000 section 3.2), the noise law in
//      seed 000's and seed 004's forms (seed 004 section 5), seed 004's noise-exponent test,
//   3. (method joint) refine poses, landmarks, radius and bias together from every reading.
// And the oracle: the same fits against true distances.

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "calibration/joint_refinement.hpp"
#include "calibration/range_model_fit.hpp"
#include "calibration/triangulation.hpp"
#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"

namespace lidarcal::calibration {

enum class Method { closed_form, joint };
const char* toString(Method m);

/// How the joint refinement picks its order among 1..max_order.
enum class JointOrderRule {
  aic,              ///< smallest AIC
  aic_parsimonious, ///< smallest order whose AIC is within 2 of the smallest (Burnham & Anderson)
  bic,              ///< smallest BIC
};
const char* toString(JointOrderRule r);

struct CalibrationConfig {
  Method method = Method::joint;                      ///< closed form of the paper, or joint refinement
  int max_order = 4;                                  ///< n_max of seed 000 phase 1
  OrderRule closed_form_rule = OrderRule::aic;        ///< order rule of the closed form
  JointOrderRule joint_rule = JointOrderRule::aic_parsimonious;  ///< order rule of the joint refinement
  NoiseKind noise = NoiseKind::squared;               ///< noise law of the calibrated model
  TriangulationConfig triangulation;                  ///< stage 1 settings
  JointConfig joint;                                  ///< stage 3 settings (order is chosen here)
  /// The stops must span at least this distance (metres) for the landmarks to be triangulated
  /// from bearings; below it calibrate() returns status no_baseline. Default 0.1 m.
  double min_baseline_m = 0.1;
  /// Progress of the joint refinement for a display (the library never prints): called with the
  /// stage name ("joint refinement"), the solves done and the solves in all (the settling pass,
  /// one per order, the covariance). Default empty: not called.
  std::function<void(const char* stage, std::size_t done, std::size_t total)> progress;
  /// Threads for the joint refinement's orders (independent solves from one settled geometry;
  /// the result does not depend on the number). 0: the machine's cores, at most 8. Default 0.
  int threads = 0;
  void validate() const;                              ///< throws std::invalid_argument
};

/// Pairs (estimated distance, reading) of the closed form: the beam nearest each landmark
/// centre, distance from the commanded stop to the triangulated circle along that beam.
/// `per_scan` false: averaged per (landmark, stop, part) as in seed 000; true: one per scan.
std::vector<RangePair> closedFormPairs(const LandmarkObservations& obs, const std::vector<LandmarkEstimate>& landmarks,
                                       double radius_m, bool per_scan);

/// Common radius: the known one, else the median of the fitted radii.
double landmarkRadius(const LandmarkObservations& obs);

/// Why stops at these poses cannot triangulate landmarks (they span less than
/// config.min_baseline_m: the sensor turned or stood still), or nothing when they can.
std::optional<std::string> baselineProblem(const std::vector<Pose2>& stops, const CalibrationConfig& config);

/// Calibrates. The result's status is "ok" or says why the data cannot support a model.
CalibrationModel calibrate(const LandmarkObservations& obs, const CalibrationConfig& config);

/// Corrections beyond this fraction of the distance (at 0.5 m or more) inside the fitted range
/// draw a warning.
inline constexpr double kImplausibleCorrection = 0.25;

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

/// The oracle of seed 004: the same fits against known distances (pairs' d_m are true).
/// `batches` (optional) feed the noise-exponent test; orders that cannot be inverted over the
/// reading window [range_min_m, range_max_m] are not chosen (no check with the defaults).
CalibrationModel calibrateAgainstTruth(const std::vector<RangePair>& pairs, const CalibrationConfig& config,
                                       const std::vector<std::vector<double>>& batches = {}, double range_min_m = 0.0,
                                       double range_max_m = 1e9);

/// Readings grouped by constant true distance: (stop, landmark, beam) across the scans of a stop.
std::vector<std::vector<double>> constantDistanceBatches(const LandmarkObservations& obs);

}  // namespace lidarcal::calibration
