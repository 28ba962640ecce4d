// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/predictive_report.hpp"

#include <cmath>
#include <utility>

#include "common/plural.hpp"
#include "io/json_number.hpp"
#include "pipeline/reports/model_text.hpp"
#include "pipeline/reports/papers.hpp"

namespace lidarcal::pipeline {
namespace {

using ojson = nlohmann::ordered_json;
using calibration::PredictiveCheck;

std::string mm(double v, bool sign = false) { return fixedOrDash(1000.0 * v, 1, sign); }

std::string share(std::size_t k, std::size_t n) {
  return std::to_string(k) + " of " + std::to_string(n) +
         (n ? " (" + fixed(100.0 * static_cast<double>(k) / static_cast<double>(n), 0) + " %)"
            : std::string());
}

}  // namespace

ojson predictiveJson(const PredictiveCheck& c) {
  ojson entries = ojson::array();
  for (const auto& e : c.entries) {
    ojson j{{"entry", e.entry}, {"reference_m", e.reference_m}, {"checked", e.checked}};
    if (e.checked) {
      j["error_m"] = e.error_m;
      j["curve_se_m"] = io::jsonNumber(e.curve_se_m);
      j["predictive_se_m"] = io::jsonNumber(e.predictive_se_m);
      j["measured_se_m"] = io::jsonNumber(e.measured_se_m);
      j["tape_sigma_m"] = e.tape_sigma_m;
      j["interval_se_m"] = io::jsonNumber(e.interval_se_m);
      j["factor_68"] = e.factor_68;
      j["factor_95"] = e.factor_95;
      j["inside_68"] = e.inside_68;
      j["inside_95"] = e.inside_95;
      j["inside_curve_95"] = e.inside_curve_95;
    }
    entries.push_back(j);
  }
  const Discrepancy& d = c.discrepancy;
  ojson j{{"discrepancy",
           {{"method", d.method}, {"sigma_m", io::jsonNumber(d.sigma_m)}, {"dof", d.dof}}},
          {"factor_68", io::jsonNumber(c.factor_68)},
          {"factor_95", io::jsonNumber(c.factor_95)}};
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
