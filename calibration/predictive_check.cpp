// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/predictive_check.hpp"

#include <cmath>
#include <utility>

#include "calibration/discrepancy.hpp"

namespace lidarcal::calibration {
namespace {

/// Whether the readings at the entry's distance were corrected under the model's policy.
bool corrected(const ReferenceMatch& m, const CalibrationModel& model, Outside outside) {
  if (!model.fitted_range_m || outside == Outside::linear || outside == Outside::extrapolate)
    return true;
  return m.surface_m >= model.fitted_range_m->first - 1e-3 &&
         m.surface_m <= model.fitted_range_m->second + 1e-3;
}

EntryInterval entryInterval(const ReferenceMatch& m, const Reference& ref,
                            const CalibrationModel& model, const ReadingCorrector& correct) {
  EntryInterval e;
  e.entry = m.entry;
  e.reference_m = m.reference_m;
  if (!m.ok() || !corrected(m, model, correct.window.outside)) return e;
  const CorrectionErrors se = correct.errorsAt(m.surface_m);
  e.error_m = m.measured_m - m.reference_m;
  e.curve_se_m = se.curve_m;
  e.predictive_se_m = se.predictive_m;
  e.measured_se_m = std::isfinite(m.measured_se_m) ? m.measured_se_m : 0.0;
  e.tape_sigma_m = m.entry < ref.distances.size() ? ref.distances[m.entry].sigma_m : 0.0;
  const double other = e.measured_se_m * e.measured_se_m + e.tape_sigma_m * e.tape_sigma_m;
  e.interval_se_m = std::sqrt(e.predictive_se_m * e.predictive_se_m + other);
  if (!std::isfinite(e.interval_se_m)) return e;
  e.checked = true;
  const double known = knownShare(e.predictive_se_m * e.predictive_se_m, other);
  e.factor_68 = predictiveFactor(model.discrepancy, kLevel68, known);
  e.factor_95 = predictiveFactor(model.discrepancy, kLevel95, known);
  e.inside_68 = std::abs(e.error_m) <= e.factor_68 * e.interval_se_m;
  e.inside_95 = std::abs(e.error_m) <= e.factor_95 * e.interval_se_m;
  e.inside_curve_95 = std::abs(e.error_m) <= 1.96 * std::sqrt(e.curve_se_m * e.curve_se_m + other);
  return e;
}

}  // namespace

PredictiveCheck predictiveCheck(const std::vector<ReferenceMatch>& matches, const Reference& ref,
                                const CalibrationModel& model, const ReadingCorrector& correct) {
  PredictiveCheck c;
  c.discrepancy = model.discrepancy;
  c.factor_68 = predictiveFactor(model.discrepancy, kLevel68);
  c.factor_95 = predictiveFactor(model.discrepancy, kLevel95);
  for (const auto& m : matches) {
    const EntryInterval e = entryInterval(m, ref, model, correct);
    c.checked += e.checked;
    c.inside_68 += e.checked && e.inside_68;
    c.inside_95 += e.checked && e.inside_95;
    c.inside_curve_95 += e.checked && e.inside_curve_95;
    c.entries.push_back(e);
  }
  return c;
}

}  // namespace lidarcal::calibration
