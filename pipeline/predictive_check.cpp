// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/predictive_check.hpp"

#include <cmath>
#include <utility>

#include "calibration/discrepancy.hpp"
#include "common/plural.hpp"
#include "pipeline/model_text.hpp"
#include "pipeline/papers.hpp"

namespace lidarcal::pipeline {
namespace {

using ojson = nlohmann::ordered_json;

ojson number(double v) { return std::isfinite(v) ? ojson(v) : ojson(nullptr); }

/// Whether the readings at the entry's distance were corrected under the model's policy.
bool corrected(const calibration::ReferenceMatch& m, const CalibrationModel& model,
               calibration::Outside outside) {
  if (!model.fitted_range_m || outside == calibration::Outside::linear ||
      outside == calibration::Outside::extrapolate)
    return true;
  return m.surface_m >= model.fitted_range_m->first - 1e-3 &&
         m.surface_m <= model.fitted_range_m->second + 1e-3;
}

EntryInterval entryInterval(const calibration::ReferenceMatch& m, const Reference& ref,
                            const CalibrationModel& model,
                            const calibration::ReadingCorrector& correct) {
  EntryInterval e;
  e.entry = m.entry;
  e.reference_m = m.reference_m;
  if (!m.ok() || !corrected(m, model, correct.window.outside)) return e;
  const calibration::CorrectionErrors se = correct.errorsAt(m.surface_m);
  e.error_m = m.measured_m - m.reference_m;
  e.curve_se_m = se.curve_m;
  e.predictive_se_m = se.predictive_m;
  e.measured_se_m = std::isfinite(m.measured_se_m) ? m.measured_se_m : 0.0;
  e.tape_sigma_m = m.entry < ref.distances.size() ? ref.distances[m.entry].sigma_m : 0.0;
  const double other = e.measured_se_m * e.measured_se_m + e.tape_sigma_m * e.tape_sigma_m;
  e.interval_se_m = std::sqrt(e.predictive_se_m * e.predictive_se_m + other);
  if (!std::isfinite(e.interval_se_m)) return e;
  e.checked = true;
  const double known = calibration::knownShare(e.predictive_se_m * e.predictive_se_m, other);
  e.factor_68 = calibration::predictiveFactor(model.discrepancy, kLevel68, known);
  e.factor_95 = calibration::predictiveFactor(model.discrepancy, kLevel95, known);
  e.inside_68 = std::abs(e.error_m) <= e.factor_68 * e.interval_se_m;
  e.inside_95 = std::abs(e.error_m) <= e.factor_95 * e.interval_se_m;
  e.inside_curve_95 = std::abs(e.error_m) <= 1.96 * std::sqrt(e.curve_se_m * e.curve_se_m + other);
  return e;
}

std::string mm(double v, bool sign = false) {
  return std::isfinite(v) ? fixed(1000.0 * v, 1, sign) : std::string("-");
}

std::string share(std::size_t k, std::size_t n) {
  return std::to_string(k) + " of " + std::to_string(n) +
         (n ? " (" + fixed(100.0 * static_cast<double>(k) / static_cast<double>(n), 0) + " %)"
            : std::string());
}

}  // namespace

PredictiveCheck predictiveCheck(const std::vector<calibration::ReferenceMatch>& matches,
                                const Reference& ref, const CalibrationModel& model,
                                const calibration::ReadingCorrector& correct) {
  PredictiveCheck c;
  c.discrepancy = model.discrepancy;
  c.factor_68 = calibration::predictiveFactor(model.discrepancy, kLevel68);
  c.factor_95 = calibration::predictiveFactor(model.discrepancy, kLevel95);
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

ojson predictiveJson(const PredictiveCheck& c) {
  ojson entries = ojson::array();
  for (const auto& e : c.entries) {
    ojson j{{"entry", e.entry}, {"reference_m", e.reference_m}, {"checked", e.checked}};
    if (e.checked) {
      j["error_m"] = e.error_m;
      j["curve_se_m"] = number(e.curve_se_m);
      j["predictive_se_m"] = number(e.predictive_se_m);
      j["measured_se_m"] = number(e.measured_se_m);
      j["tape_sigma_m"] = e.tape_sigma_m;
      j["interval_se_m"] = number(e.interval_se_m);
      j["factor_68"] = e.factor_68;
      j["factor_95"] = e.factor_95;
      j["inside_68"] = e.inside_68;
      j["inside_95"] = e.inside_95;
      j["inside_curve_95"] = e.inside_curve_95;
    }
    entries.push_back(j);
  }
  const Discrepancy& d = c.discrepancy;
  ojson j{{"discrepancy", {{"method", d.method}, {"sigma_m", number(d.sigma_m)}, {"dof", d.dof}}},
          {"factor_68", number(c.factor_68)},
          {"factor_95", number(c.factor_95)}};
  const std::pair<const char*, std::size_t> counts[] = {{"checked", c.checked},
                                                        {"inside_68", c.inside_68},
                                                        {"inside_95", c.inside_95},
                                                        {"inside_curve_95", c.inside_curve_95}};
  for (const auto& [key, count] : counts) j[key] = count;
  j["entries"] = entries;
  return j;
}

std::string predictiveTable(const PredictiveCheck& c) {
  std::string s =
      "\nEach measured distance against the model's intervals (corrected - reference; the "
      "interval's standard error "
      "combines the correction's predictive standard error, the scans' and the tape's):\n\n"
      "| entry | reference [m] | corrected - reference [mm] | curve SE [mm] | predictive SE [mm] | "
      "tape [mm] | "
      "predictive 95 % interval [mm] | inside 68 % | inside 95 % "
      "|\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& e : c.entries) {
    s += "| " + std::to_string(e.entry) + " | " + fixed(e.reference_m, 3) + " | ";
    if (!e.checked) {
      s += "- | - | - | - | - | - | - |\n";
      continue;
    }
    s += mm(e.error_m, true) + " | " + mm(e.curve_se_m) + " | " + mm(e.predictive_se_m) + " | " +
         mm(e.tape_sigma_m) + " | +-" + mm(e.factor_95 * e.interval_se_m) + " | " +
         (e.inside_68 ? "yes" : "no") + " | " + (e.inside_95 ? "yes" : "no") + " |\n";
  }
  const Discrepancy& d = c.discrepancy;
  s += "\nInside the predictive intervals: 68 %: " + share(c.inside_68, c.checked) +
       ", 95 %: " + share(c.inside_95, c.checked) +
       "; inside the curve's 95 % interval (+-1.96 curve SE, with the scans' and the "
       "tape's): " +
       share(c.inside_curve_95, c.checked) + ". ";
  if (d.estimated())
    s += "Model discrepancy " + fixed(1000.0 * d.sigma_m, 1) + " mm (" + d.method + ", " +
         plural(d.dof, "degree") + " of freedom; " + papers::kDiscrepancy +
         "), Student-t factors " + fixed(c.factor_68, 2) + " and " + fixed(c.factor_95, 2) +
         " for the correction alone, nearer the normal's where an entry's known tape and "
         "scan errors make up part of its interval (Welch-Satterthwaite).\n";
  else
    s += "The model has no discrepancy estimate: its predictive interval is the curve's (" +
         d.note + ").\n";
  return s;
}

}  // namespace lidarcal::pipeline
