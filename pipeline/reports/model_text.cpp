// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/model_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <tuple>

#include "calibration/discrepancy.hpp"
#include "calibration/error_summary.hpp"
#include "calibration/held_out.hpp"
#include "common/pose2.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {
std::string polynomialText(const std::vector<double>& a, const std::vector<double>& se) {
  std::string s;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (i)
      s += a[i] < 0 ? " - " : " + ";
    else if (a[i] < 0)
      s += "-";
    s += fixed(std::abs(a[i]), 5);
    if (i < se.size() && std::isfinite(se[i]))
      s += se[i] == 0.0 ? std::string(" (fixed)") : " (+-" + fixed(se[i], 5) + ")";
    if (i == 1) s += " d";
    if (i > 1) s += " d^" + std::to_string(i);
  }
  return s;
}

std::vector<double> coefficientErrors(const CalibrationModel& m) {
  const std::size_t n = m.model.bias.alpha.size();
  std::vector<double> se(n, std::numeric_limits<double>::quiet_NaN());
  if (m.alpha_covariance.size() != n * n) return se;
  for (std::size_t i = 0; i < n; ++i)
    se[i] = std::sqrt(std::max(0.0, m.alpha_covariance[i * n + i]));
  return se;
}

double biasError(const CalibrationModel& m, double d) {
  return calibration::curveStandardError(m, d);
}

double predictiveHalfWidth(const CalibrationModel& m, double d, double level) {
  return calibration::predictiveFactor(m.discrepancy, level) *
         calibration::predictiveStandardError(biasError(m, d), m.discrepancy);
}

std::string discrepancyText(const CalibrationModel& m) {
  const Discrepancy& q = m.discrepancy;
  if (!q.estimated()) return "model discrepancy " + q.note;
  std::string s = "model discrepancy " + fixed(1000.0 * q.sigma_m, 1) + " mm, REML over " +
                  plural(q.entries, "measured distance") + " (" +
                  plural(static_cast<std::size_t>(q.dof), "degree") + " of freedom";
  if (std::isfinite(q.tape_sigma_m) && q.tape_sigma_m > 0.0)
    s += ", stated tape error " + fixed(1000.0 * q.tape_sigma_m, 1) + " mm";
  return s + "): " + q.note;
}

std::string polynomialWithErrors(const CalibrationModel& m) {
  return polynomialText(m.model.bias.alpha, coefficientErrors(m));
}

std::vector<double> tableDistances(const CalibrationModel& m) {
  double lo = m.model.range_min_m, hi = std::min(m.model.range_max_m, 10.0);
  if (m.fitted_range_m) std::tie(lo, hi) = *m.fitted_range_m;
  if (!(hi > lo)) return {};
  // About five round distances inside [lo, hi], on a 1-2-5 step.
  double step = 0.1;
  for (double s : {0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0}) {
    step = s;
    if ((hi - lo) / s <= 6.0) break;
  }
  std::vector<double> d;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9; v += step)
    if (v > 0.0) d.push_back(v);
  if (d.empty()) d.push_back(0.5 * (lo + hi));
  return d;
}

std::string orderText(const CalibrationModel& m) {
  const std::vector<double> se = coefficientErrors(m);
  const bool offset_only = se.size() == 2 && se[1] == 0.0 && m.model.bias.alpha[1] == 1.0;
  return offset_only ? "an offset only (order 0)" : "order " + std::to_string(m.model.bias.order());
}

namespace {

/// "  0.50 m: -6.2 +- 2.4 mm;  1.00 m: ..." at tableDistances(m), each error followed by
/// what `interval` gives for its distance, ending in a newline.
template <class Interval>
std::string errorList(const CalibrationModel& m, Interval interval) {
  std::string s;
  for (double d : tableDistances(m)) {
    if (!s.empty()) s += ";";
    s += "  " + fixed(d, 2) + " m: " + fixed(1000.0 * (m.model.bias(d) - d), 1, true) +
         interval(d) + " mm";
  }
  return s + "\n";
}

}  // namespace

std::string modelSummary(const CalibrationModel& m) {
  std::string s;
  s += "  range model (" + m.method + ", " + orderText(m) +
       "): reading = " + polynomialWithErrors(m) + "   (d in m; +- one standard error)\n";
  if (m.fitted_range_m)
    s += "  fitted over true distances " + fixed(m.fitted_range_m->first, 3) + "-" +
         fixed(m.fitted_range_m->second, 3) + " m (readings " +
         fixed(m.model.bias(m.fitted_range_m->first), 3) + "-" +
         fixed(m.model.bias(m.fitted_range_m->second), 3) +
         " m; the beams' distances to the surfaces they hit, for a pole's nearest point its centre "
         "distance minus "
         "its radius); `correct` continues the correction "
         "beyond them at its slope at the edge (--outside)\n";
  const bool errors =
      m.alpha_covariance.size() == m.model.bias.alpha.size() * m.model.bias.alpha.size();
  s += "  error of the raw reading (f(d) - d)" +
       std::string(errors ? " +- curve SE (how well the polynomial is pinned down)" : "") + ":" +
       errorList(m, [&](double d) {
         return errors ? " +- " + fixed(1000.0 * biasError(m, d), 1) : std::string();
       });
  if (errors) {
    s += "  predictive 95 % interval of that error at a distance the fit did not see (curve and "
         "model discrepancy):" +
         errorList(m, [&](double d) {
           return " +- " + fixed(1000.0 * predictiveHalfWidth(m, d, 0.95), 1);
         });
    s += "    (" + discrepancyText(m) + ")\n";
  }
  for (const auto& w : m.warnings) s += "  warning: " + w + "\n";
  return s;
}

std::string beyondFitText(const calibration::FilteringStats& s, const CalibrationModel& m,
                          calibration::Outside outside) {
  const std::size_t returns = s.corrected + s.beyond() + s.unresolved;
  if (s.beyond() == 0 || returns == 0 || !m.fitted_range_m) return "";
  const double share = static_cast<double>(s.beyond()) / static_cast<double>(returns);
  const auto [lo, hi] = *m.fitted_range_m;
  std::string fate;
  switch (outside) {
    case calibration::Outside::linear:
      fate =
          "corrected by continuing the fitted correction past the edge at its slope there "
          "(--outside linear; "
          "marked 2 in the `correction` field, with a standard error that grows with the distance "
          "past the edge)";
      break;
    case calibration::Outside::extrapolate:
      fate = "corrected with the polynomial itself (--outside extrapolate)";
      break;
    case calibration::Outside::keep:
      fate = "left as read (--outside keep)";
      break;
    case calibration::Outside::drop:
      fate = "dropped (--outside drop)";
      break;
  }
  std::string where;
  if (s.below > 0)
    where =
        std::to_string(s.below) + " below it, readings down to " + fixed(s.beyond_min_m, 2) + " m";
  if (s.beyond() > s.below)
    where += (where.empty() ? "" : "; ") + std::to_string(s.beyond() - s.below) +
             " above it, readings up to " + fixed(s.beyond_max_m, 2) + " m";
  std::string t = plural(s.beyond(), "return") + " (" + fixed(100.0 * share, 1) +
                  " % of the returns) lie beyond the true distances the model was fitted on (" +
                  fixed(lo, 2) + "-" + fixed(hi, 2) + " m; " + where + "): " + fate + ".";
  if (share > 0.5)
    t += "\nwarning: most of the returns lie beyond the fitted range, so most of the output rests "
         "on an "
         "extrapolation. Record the poles over the whole span of distances the sensor will be used "
         "at (here readings " +
         fixed(std::min(s.beyond_min_m, m.model.bias(lo)), 1) + "-" +
         fixed(std::max(s.beyond_max_m, m.model.bias(hi)), 1) + " m), and calibrate again.";
  return t;
}

namespace {

/// RMS of the finite values +- its standard error over them, "X +- Y mm" ("X mm" with one value,
/// "-" with none).
std::string rmsMm(const std::vector<double>& v) {
  std::vector<double> finite;
  for (double e : v)
    if (std::isfinite(e)) finite.push_back(e);
  const calibration::RmsError r = calibration::rmsError(finite);
  if (!r.entries) return "-";
  return fixed(1000.0 * r.rms_m, 1) +
         (std::isfinite(r.se_m) ? " +- " + fixed(1000.0 * r.se_m, 1) : std::string()) + " mm";
}

}  // namespace

std::string referenceTable(const std::vector<calibration::ReferenceMatch>& raw,
                           const std::vector<calibration::ReferenceMatch>* corrected,
                           const CalibrationModel* model, calibration::Outside outside) {
  auto inside = [&](const calibration::ReferenceMatch& m) {
    return !model || !model->fitted_range_m ||
           (m.surface_m >= model->fitted_range_m->first - 1e-3 &&
            m.surface_m <= model->fitted_range_m->second + 1e-3);
  };
  const bool beyond_corrected =
      outside == calibration::Outside::linear || outside == calibration::Outside::extrapolate;
  std::string s = "| entry | stop | target | reference [m] | raw [m] | raw - reference [mm] |";
  if (corrected) s += " corrected [m] | corrected - reference [mm] |";
  s += " scans | readings |\n|---|---|---|---|---|---|";
  if (corrected) s += "---|---|";
  s += "---|---|\n";
  // measured - reference of the entries counted
  std::vector<double> e_raw, e_cor, pair_raw, pair_cor;
  std::size_t left_out = 0;
  auto cell = [](const calibration::ReferenceMatch& m, bool counted, std::vector<double>& errors) {
    if (!m.ok()) return std::string(" not found | - |");
    const double e = m.measured_m - m.reference_m;
    if (counted) errors.push_back(e);
    const std::string se =
        std::isfinite(m.measured_se_m) ? " +- " + fixed(m.measured_se_m, 4) : std::string();
    return " " + fixed(m.measured_m, 4) + se + " | " + fixed(1000.0 * e, 1, true) + " |";
  };
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const auto& m = raw[k];
    const bool in = inside(m);
    const bool counted = in || beyond_corrected;
    left_out += !counted;
    s += "| " + std::to_string(m.entry) + (in ? "" : " (beyond the fitted range)") + " | " +
         std::to_string(m.stop) + " | " +
         (m.target == ReferenceTarget::wall ? "wall" : "landmark " + std::to_string(m.landmark)) +
         " | " + fixed(m.reference_m, 3) + " |" + cell(m, counted, e_raw);
    const calibration::ReferenceMatch* c =
        corrected && k < corrected->size() ? &(*corrected)[k] : nullptr;
    if (corrected) s += c ? cell(*c, counted, e_cor) : std::string(" - | - |");
    if (counted && c && m.ok() && c->ok())
      pair_raw.push_back(m.measured_m - m.reference_m),
          pair_cor.push_back(c->measured_m - c->reference_m);
    s += " " + std::to_string(m.sightings) + " | " + std::to_string(m.readings) + " |\n";
  }
  s += "\nRMS of measured - reference: raw " + rmsMm(e_raw);
  if (corrected) s += ", corrected " + rmsMm(e_cor);
  s += " (over " + plural(e_raw.size(), "entry", "entries") +
       "; +- one standard error over the entries";
  if (left_out)
    s += "; " + std::to_string(left_out) + " beyond the fitted range left out: --outside " +
         calibration::toString(outside) + " does not correct their readings";
  s += ")\n";
  if (corrected && !pair_raw.empty()) {
    const calibration::MseRatio q = calibration::mseRatio(pair_raw, pair_cor);
    if (std::isfinite(q.ratio)) {
      s += "MSE ratio raw / corrected (" + std::string(papers::kLandmarks) +
           ", eq. 31; above 1 the correction helps): " + fixed(q.ratio, 2);
      if (std::isfinite(q.low))
        s += ", 95 % interval " + fixed(q.low, 2) + "-" + fixed(q.high, 2) + " (paired over " +
             plural(q.entries, "entry", "entries") + ")" +
             (q.low > 1.0    ? ": the correction helps on these distances"
              : q.high < 1.0 ? ": the correction makes these distances worse"
                             : ": these entries cannot tell whether the correction helps");
      s += "\n";
    }
  }
  return s;
}

namespace {

std::string mm(double v) { return fixedOrDash(1000.0 * v, 1, true); }

std::string wallText(const calibration::SpanWall& w) {
  return fixed(rad2deg(w.normal_rad), 0) + " deg at " + fixed(w.distance_m, 3) + " m";
}

}  // namespace

std::string spanTable(const calibration::SpanReadings& found,
                      const std::vector<calibration::SpanCheck>& checks) {
  std::string s =
      "| entry | stop | walls (normal, distance as read) | measured [m] | raw - measured [mm] | "
      "fitted - measured [mm] | left out - measured [mm] |\n|---|---|---|---|---|---|---|\n";
  std::vector<double> raw, fitted, left_out;
  for (const auto& c : checks) {
    std::string walls = "(tape distance)";
    for (const auto& m : found.matches)
      if (c.entry == "spans[" + std::to_string(m.entry) + "]" && m.ok())
        walls = wallText(found.walls[m.wall_a]) + ", " + wallText(found.walls[m.wall_b]);
    s += "| " + c.entry + " | " + std::to_string(c.stop) + " | " + walls + " | " +
         fixed(c.reference_m, 3) + " | " + mm(c.raw_error_m) + " | " + mm(c.fitted_error_m) +
         " | " + mm(c.left_out_error_m) + " |\n";
    raw.push_back(c.raw_error_m);
    fitted.push_back(c.fitted_error_m);
    left_out.push_back(c.left_out_error_m);
  }
  s += "\nRMS of what the sensor says - measured: raw " + rmsMm(raw) + ", fitted " + rmsMm(fitted) +
       ", left out " + rmsMm(left_out) + " (over " + plural(checks.size(), "entry", "entries") +
       "; +- one standard error over the entries; left out: fitted without the entry and every "
       "other span between the same two walls; - where the other "
       "entries cannot determine the model's order)\n";
  return s;
}

std::string spanEvaluationTable(const std::vector<calibration::SpanMatch>& raw,
                                const std::vector<calibration::SpanMatch>* corrected) {
  std::string s = "| entry | stop | measured [m] | raw [m] | raw - measured [mm] |";
  if (corrected) s += " corrected [m] | corrected - measured [mm] |";
  s += " scans |\n|---|---|---|---|---|";
  if (corrected) s += "---|---|";
  s += "---|\n";
  std::vector<double> raw_errors, cor_errors;
  auto cell = [](const calibration::SpanMatch& m, std::vector<double>& errors) {
    if (!m.ok()) return std::string(" not found | - |");
    errors.push_back(m.measured_m - m.reference_m);
    const std::string se =
        std::isfinite(m.measured_se_m) ? " +- " + fixed(m.measured_se_m, 4) : std::string();
    return " " + fixed(m.measured_m, 4) + se + " | " + mm(m.measured_m - m.reference_m) + " |";
  };
  for (std::size_t k = 0; k < raw.size(); ++k) {
    s += "| spans[" + std::to_string(raw[k].entry) + "] | " + std::to_string(raw[k].stop) + " | " +
         fixed(raw[k].reference_m, 3) + " |" + cell(raw[k], raw_errors);
    if (corrected)
      s += k < corrected->size() ? cell((*corrected)[k], cor_errors) : std::string(" - | - |");
    s += " " + std::to_string(raw[k].scans) + " |\n";
  }
  s += "\nRMS of the spans as the scans measure them - measured: raw " + rmsMm(raw_errors);
  if (corrected) s += ", corrected " + rmsMm(cor_errors);
  s += " (+- one standard error over the spans)\n";
  return s;
}

}  // namespace lidarcal::pipeline
