// SPDX-License-Identifier: BSD-3-Clause
#include "watch/watch_settings.hpp"

#include <cmath>
#include <stdexcept>

namespace lidarcal::watch {

const char* toString(Mode m) { return m == Mode::learn ? "learn" : "watch"; }

bool parseMode(const std::string& text, Mode& out) {
  if (text == "watch") return out = Mode::watch, true;
  if (text == "learn") return out = Mode::learn, true;
  return false;
}

const char* toString(Exposure e) { return e == Exposure::time ? "hour" : "km"; }

void WatchSettings::validate() const {
  auto fail = [](const char* field, const char* what) {
    throw std::invalid_argument(std::string("WatchSettings.") + field + ": " + what);
  };
  if (!(false_alarms.per_unit > 0.0) || !std::isfinite(false_alarms.per_unit))
    fail("false_alarms.per_unit", "must be > 0");
  if (!(check.every_m > 0.0) || !std::isfinite(check.every_m)) fail("check.every_m", "must be > 0");
  if (check.max_scans < 10) fail("check.max_scans", "must be >= 10");
  if (check.min_sightings < 2) fail("check.min_sightings", "must be >= 2");
  if (check.baseline_checks < 2) fail("check.baseline_checks", "must be >= 2");
  if (check.record_checks < check.baseline_checks)
    fail("check.record_checks", "must be >= check.baseline_checks");
  if (!(check.stale_after_spans >= 1.0)) fail("check.stale_after_spans", "must be >= 1");
  if (check.landmark_radius_m && !(*check.landmark_radius_m > 0.0))
    fail("check.landmark_radius_m", "must be > 0");
  if (check.bias_replicas < 0 || check.bias_replicas > 100)
    fail("check.bias_replicas", "must be in 0..100");
  if (learn.max_order < 1 || learn.max_order > 6) fail("learn.max_order", "must be in 1..6");
  if (!(learn.max_standard_error_m > 0.0)) fail("learn.max_standard_error_m", "must be > 0");
  if (!(learn.switch_level > 0.0 && learn.switch_level < 1.0))
    fail("learn.switch_level", "must be in (0, 1)");
  if (learn.max_scans < check.max_scans) fail("learn.max_scans", "must be >= check.max_scans");
  if (threads < 0) fail("threads", "must be >= 0");
  detection.validate();
  association.validate();
}

WatchSettings defaultWatchSettings() {
  WatchSettings s;
  s.association.drift_per_m = 0.2;  // as `detect` for continuous motion (sequence_detector.hpp)
  s.association.forget_after_stops = 200;
  s.association.forget_landmarks_after_stops = s.learn.max_scans;
  return s;
}

}  // namespace lidarcal::watch
