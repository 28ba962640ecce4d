// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Stage 2 of calibrate(): the closed form of Alhashimi et al. 2021 (section 3.2). Distances from
// the triangulated landmarks to the stops along the central beams, the bias polynomial for orders
// 0..n_max with the order chosen by AIC (or held-out validation), the noise law, and the bias
// covariance by a delete-a-group jackknife over the stops. It seeds the joint refinement.

#include <cstddef>
#include <vector>

#include "calibration/calibration_config.hpp"
#include "calibration/range_model_fit.hpp"
#include "calibration/triangulation.hpp"
#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"

namespace lidarcal::calibration {

/// Pairs (estimated distance, reading) of the closed form: the beam nearest each landmark
/// centre, distance from the commanded stop to the triangulated circle along that beam.
/// `per_scan` false: averaged per (landmark, stop, part) as in Alhashimi et al. 2021; true: one
/// per scan. Parts split the data into fit / choose / test thirds (section 4.3).
std::vector<RangePair> closedFormPairs(const LandmarkObservations& obs,
                                       const std::vector<LandmarkEstimate>& landmarks,
                                       double radius_m, bool per_scan);

/// Common radius, metres: the known one, else the median of the fitted radii.
double landmarkRadius(const LandmarkObservations& obs);

/// Readings grouped by constant true distance: (stop, landmark, beam) across the scans of a stop.
std::vector<std::vector<double>> constantDistanceBatches(const LandmarkObservations& obs);

/// Orders whose f cannot be inverted over the sensor's reading window [range_min_m,
/// range_max_m] are not candidates: the filtering stage could not use them (and they only arise
/// from overfitting).
Admissible invertibleOver(double range_min_m, double range_max_m);

/// The order table of `sel` into m.orders (BIC from the AIC over `n` pairs), with the orders
/// chosen by AIC and by validation and the rule's name.
void fillOrders(CalibrationModel& m, const OrderSelection& sel, std::size_t n);

/// RMS of y - f(d), metres; 0 without pairs.
double rmsResidual(const BiasPolynomial& f, const std::vector<double>& d,
                   const std::vector<double>& y);

/// What the closed form found, before it goes into the model.
struct ClosedFormSeed {
  std::size_t pairs = 0;     ///< averaged landmark-stop distances the order was chosen on
  OrderSelection selection;  ///< every order's fit and the rule's choice
  int order = 1;  ///< the order used: the chosen one, at least 1 (order 0 cannot be inverted)
  std::vector<double> d_m;  ///< per-scan landmark-stop distances, metres
  std::vector<double> y_m;  ///< their readings, metres
};

/// Selects the order on the averaged `pairs` (closedFormPairs, per_scan false; only invertible
/// orders when the sensor's window is known) and collects the per-scan pairs.
ClosedFormSeed closedFormSeed(const LandmarkObservations& obs,
                              const std::vector<LandmarkEstimate>& tri, double radius_m,
                              const std::vector<RangePair>& pairs, const CalibrationConfig& config);

/// The closed form into the model: order table, bias at seed.order, noise law (config.noise),
/// residual RMS, readings, bearing scatter sigma_theta, stop poses and fitted range.
void fillClosedForm(CalibrationModel& m, const LandmarkObservations& obs,
                    const std::vector<LandmarkEstimate>& tri, const ClosedFormSeed& seed,
                    const CalibrationConfig& config);

/// Groups of the delete-a-group jackknife of the closed form: at most this many, each a run of
/// consecutive stops (a stop each when there are fewer stops).
inline constexpr std::size_t kClosedFormJackknifeGroups = 20;

/// Covariance of the closed form's bias at `order` (row-major): the delete-a-group jackknife over
/// the stops, (G - 1)/G sum_g (alpha_-g - mean)(alpha_-g - mean)^T, each alpha_-g from the
/// triangulation and the fit redone without group g. Alhashimi et al. 2021's closed form has no
/// covariance of its own (its distances are themselves estimated from the same data); this one
/// includes the triangulation's error. Empty when fewer than 3 groups leave enough pairs.
std::vector<double> closedFormCovariance(const LandmarkObservations& obs,
                                         const CalibrationConfig& config, double radius_m,
                                         int order);

}  // namespace lidarcal::calibration
