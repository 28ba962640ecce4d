// SPDX-License-Identifier: BSD-3-Clause
#include "watch/diagnostics.hpp"

#include <cmath>
#include <cstdio>

#include "calibration/model_comparison.hpp"
#include "common/number_text.hpp"

namespace lidarcal::watch {

namespace {

/// "+23.4 +- 0.8 mm" (se NaN: "+23.4 mm").
std::string mmText(double value_m, double se_m) {
  char text[64];
  if (std::isfinite(se_m))
    std::snprintf(text, sizeof text, "%+.1f +- %.1f mm", 1000.0 * value_m, 1000.0 * se_m);
  else
    std::snprintf(text, sizeof text, "%+.1f mm", 1000.0 * value_m);
  return text;
}

}  // namespace

std::string biasText(const CalibrationModel& m, double d) {
  if (!calibration::insideFittedRange(m, d)) {
    if (!m.fitted_range_m) return "outside the sensor's window";
    return "outside the fitted range " + fixed(m.fitted_range_m->first, 2) + "-" +
           fixed(m.fitted_range_m->second, 2) + " m";
  }
  const Eigen::MatrixXd c = calibration::biasCovariance(m, {d});
  return mmText(m.model.bias(d) - d, c.size() ? std::sqrt(std::max(0.0, c(0, 0))) : NAN);
}

void addBiasValues(const CalibrationModel& model,
                   std::vector<std::pair<std::string, std::string>>& values) {
  for (double d : {1.0, 2.0, 3.0})
    values.emplace_back("bias at " + fixed(d, 0) + " m", biasText(model, d));
}

DiagnosticReport diagnosticReport(const WatchState& s, const CalibrationModel* model,
                                  const WatchSettings& settings, std::size_t not_watched) {
  DiagnosticReport r;
  r.level = s.level;
  r.message = s.message;
  auto add = [&r](std::string key, std::string value) {
    r.values.emplace_back(std::move(key), std::move(value));
  };
  add("mode", toString(settings.mode));
  add("model version", std::to_string(s.model_version));
  if (model) addBiasValues(*model, r.values);
  const ModelCheck& k = s.last_check.check;
  if (s.last_check.test != Test::none)
    for (std::size_t i = 0; i < 2; ++i)
      add("last check: shift at " + fixed(k.distance_m[i], 2) + " m",
          mmText(k.shift_m[i], k.shift_se_m[i]));
  add("sightings in window", std::to_string(s.sightings));
  add("poles tracked", std::to_string(s.tracks));
  add("since last test", fixed(s.since_check_m, 1) + " m, " + fixed(s.since_check_s, 0) + " s");
  add("scans watched", std::to_string(s.scans));
  add("scans not watched", std::to_string(not_watched));
  add("checks tested", std::to_string(s.checks));
  add("alarms", std::to_string(s.alarms));
  add("switches", std::to_string(s.switches));
  add("false alarms set",
      fixed(settings.false_alarms.per_unit, 3) + " per " + toString(settings.false_alarms.unit));
  return r;
}

}  // namespace lidarcal::watch
