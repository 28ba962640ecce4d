// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/plausibility.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <Eigen/Dense>

#include "calibration/inversion.hpp"
#include "common/plural.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {

void addUnsupportedCorrectionWarning(CalibrationModel& m) {
  const std::size_t n = m.model.bias.alpha.size();
  if (!m.fitted_range_m || m.alpha_covariance.size() != n * n) return;
  const auto [lo, hi] = *m.fitted_range_m;
  double largest = 0.0, largest_se = 0.0;
  for (int i = 0; i <= 50; ++i) {
    const double d = lo + (hi - lo) * i / 50.0;
    // Standard error of f(d): that of the distance it corrects to, times f'(d).
    const double se = correctionStandardError(m.model.bias, m.alpha_covariance, d, d, d) *
                      m.model.bias.derivative(d);
    const double c = std::abs(m.model.bias(d) - d);
    if (!std::isfinite(se)) return;
    if (c > 2.0 * se) return;  // a correction the data support somewhere
    if (c > largest) largest = c, largest_se = se;
  }
  m.plausibility.correction_supported = false;
  char text[400];
  std::snprintf(text, sizeof text,
                "the correction is within two standard errors of none over the whole fitted range "
                "(at most %.1f mm, "
                "+-%.1f mm there): the data do not show that the sensor errs, and applying it may "
                "add as much error as "
                "it removes; measure more distances, or repeat each, before relying on it",
                1000.0 * largest, 1000.0 * largest_se);
  m.warnings.push_back(text);
}

RelativeCorrection largestRelativeCorrection(const BiasPolynomial& bias, double lo, double hi) {
  RelativeCorrection worst{0.0, lo, 0.0};
  for (int i = 0; i <= 50; ++i) {
    const double d = lo + (hi - lo) * i / 50.0;
    const double rel = std::abs(bias(d) - d) / std::max(d, 0.5);
    if (rel > worst.fraction) worst = {rel, d, 1000.0 * std::abs(bias(d) - d)};
  }
  return worst;
}

void addPlausibilityWarnings(CalibrationModel& m, const JointResult* j) {
  const std::size_t n = m.model.bias.alpha.size();
  char text[512];
  addUnsupportedCorrectionWarning(m);
  // An offset that trades off against the pole radius is not determined by the data: the
  // central beam reads alpha_0 + alpha_1 (|c - p| - r), and only the arcs' curvature tells r.
  if (j && j->alpha_radius_covariance.size() == static_cast<Eigen::Index>(n) &&
      j->radius_variance > 0.0 && m.alpha_covariance.size() == n * n &&
      m.alpha_covariance[0] > 0.0) {
    const double corr =
        j->alpha_radius_covariance(0) / std::sqrt(m.alpha_covariance[0] * j->radius_variance);
    m.offset_radius_correlation = corr;
    if (std::abs(corr) > 0.9) {
      m.plausibility.offset_determined = false;
      std::snprintf(text, sizeof text,
                    "the offset alpha_0 = %.1f mm (+-%.1f) trades off against the estimated pole "
                    "radius %.1f mm "
                    "(correlation %.2f): the data do not separate them, so the offset is not "
                    "determined; measure the "
                    "poles' radius and give it with --radius (or calibrate against measured "
                    "distances, --reference)",
                    1000.0 * m.model.bias.alpha[0], 1000.0 * std::sqrt(m.alpha_covariance[0]),
                    1000.0 * j->radius_m, corr);
      m.warnings.push_back(text);
    }
  }
  // Landmarks the data do not locate: with a centre uncertain by decimetres the range offset
  // can trade against where the landmark stands, and a small standard error of the offset does
  // not mean it is right. Every CARMEN office log gives this (median centre standard error
  // 0.4-90 m: its "landmarks" are furniture seen from few directions), the simulated pole fields
  // about 1 cm.
  if (j && !j->centre_covariance.empty()) {
    std::vector<double> se;
    for (const auto& [id, c] : j->centre_covariance)
      se.push_back(std::sqrt(
          std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(c).eigenvalues()(1))));
    const double typical = median(se);
    if (typical > kUnlocatedLandmarkM) {
      m.plausibility.landmarks_located = false;
      std::snprintf(
          text, sizeof text,
          "the landmarks' positions are not pinned down by the data (median standard error of a "
          "centre "
          "%.2f m over %s, against about 0.01 m for round poles seen from several stops): the "
          "offset can trade against where they stand, so its standard error understates its error; "
          "check "
          "that lidarcal detect finds round poles of one radius, record stops all around them, or "
          "calibrate against measured distances (--reference)",
          typical, plural(se.size(), "landmark").c_str());
      m.warnings.push_back(text);
    }
  }
  // Corrections far beyond what lidars are built to: more often landmarks that are not round
  // poles of one radius (corners, door frames) than a sensor that far off. The bound leaves
  // room for the strongly biased triangulation sensor of Alhashimi et al. 2021's simulations
  // (alpha = [0.0525, 0.8838, 0.0584]: +17 % at 4.9 m), which is not an error.
  if (m.fitted_range_m) {
    const auto [lo, hi] = *m.fitted_range_m;
    const RelativeCorrection worst = largestRelativeCorrection(m.model.bias, lo, hi);
    if (worst.fraction > kImplausibleCorrection) {
      m.plausibility.correction_plausible = false;
      std::snprintf(text, sizeof text,
                    "the model changes readings by up to %.0f %% (%.0f mm at %.2f m): more than "
                    "the range error of "
                    "most lidars; check that the landmarks lidarcal detect finds are round poles "
                    "of one radius (not "
                    "corners, door frames or legs of different sizes) before using it",
                    100.0 * worst.fraction, worst.mm, worst.at_m);
      m.warnings.push_back(text);
    }
  }
}

}  // namespace lidarcal::calibration
