// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Filtering stage (Alhashimi et al. 2021 section 3.2 phase 3, Alhashimi et al. 2016 section 5.2):
// the distance d that explains a raw reading y under the calibrated model.
//   LS (Alhashimi et al. 2016 eq. 30, Alhashimi et al. 2021 eq. 30): a root of f(d) = y; the root
//       inside the window nearest the reading.
//   ML (Alhashimi et al. 2016 eqs. 28-29): a root of (y - f(d)) (y - f(d) + d f'(d) / 2) =
//       sigma_e^2 d^4, the stationary points of the likelihood of model (21); the most likely one.
// Roots are found inside the window only: the roots of the derivative split it into pieces on
// which the polynomial is monotone, and each piece with a sign change is solved by Newton's
// method kept inside its bracket. For LS the pieces depend on the model alone and are computed
// once, so a reading costs a few polynomial evaluations (the ROS node's budget:
// docs/results/speed.md).

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/range_model.hpp"

namespace lidarcal::calibration {

enum class InversionMethod { ls, ml };
const char* toString(InversionMethod m);

struct InversionConfig {
  /// LS (default) or ML (needs the squared noise law)
  InversionMethod method = InversionMethod::ls;
  double d_min_m = 0.0;  ///< true distances searched in [d_min_m, d_max_m]
  double d_max_m = 1e9;  ///< (normally the sensor's range window, widened by the bias)
};

/// The window searched for a model: true distances in [0, 2 range_max_m] (generous: the bias
/// can put readings well below or above the distances).
InversionConfig inversionWindow(const RangeModel& model, InversionMethod method);

/// Distances for readings under one model; construct once, call invert() per point.
class RangeInverter {
 public:
  /// Throws std::invalid_argument for a model that cannot be inverted (order 0, or ML without
  /// a squared noise law).
  RangeInverter(const RangeModel& model, const InversionConfig& config);
  /// The corrected distance, or nothing when no root lies in the window.
  std::optional<double> invert(double y_m) const;

 private:
  std::optional<double> invertLs(double y_m) const;
  std::optional<double> invertMl(double y_m) const;
  RangeModel model_;
  InversionConfig config_;
  /// the window split where f' = 0: f - y is monotone on each piece
  std::vector<double> ls_pieces_;
};

/// Whether f is strictly increasing on [d_min, d_max] (else the inversion is ambiguous);
/// `where` receives the first distance at which f' <= 0.
bool isMonotone(const BiasPolynomial& f, double d_min_m, double d_max_m, double* where = nullptr);

/// Whether every reading in [y_min, y_max] has exactly one distance: f increases from 0 until
/// it passes y_max. `where` receives the first distance at which f' <= 0 while f < y_max (or
/// the largest distance searched, 4 y_max, when f never reaches y_max).
bool invertsReadingWindow(const BiasPolynomial& f, double y_min_m, double y_max_m,
                          double* where = nullptr);

/// Standard error (metres) of the distance that f, continued linearly beyond [d_min, d_max],
/// gives for a reading, at corrected distance d: sqrt(g' C g) / f'(e), with g the gradient of
/// f(e) + f'(e) (d - e) in the coefficients, e = d clamped to the window. NaN without covariance.
double correctionStandardError(const BiasPolynomial& f, const std::vector<double>& covariance,
                               double d_m, double d_min_m, double d_max_m);

/// The true distances a fit covers, [min, max] metres: every distance d_m of the fit's readings,
/// widened to the distances f gives for its smallest and largest reading y_m (the readings of
/// the nearest and farthest target scatter beyond f(min d) and f(max d)). d_m and y_m are the
/// same length and not empty.
std::pair<double, double> fittedRange(const std::vector<double>& d_m,
                                      const std::vector<double>& y_m, const BiasPolynomial& f);

}  // namespace lidarcal::calibration
