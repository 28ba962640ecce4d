// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the nodes put on /diagnostics for the watcher (both middlewares, one content): the level
// (OK, WARN, ERROR), the state in a sentence, and key/value pairs: the model's bias at a few
// distances with its standard error, the last check's shift, the sightings in the window, the
// time and travel since the last test, the counts.

#include <string>
#include <utility>
#include <vector>

#include "common/calibration_model.hpp"
#include "watch/events.hpp"
#include "watch/watch_settings.hpp"

namespace lidarcal::watch {

/// One diagnostic status, ROS's DiagnosticStatus without its transport.
struct DiagnosticReport {
  Health level = Health::warn;                              ///< OK, WARN or ERROR
  std::string message;                                      ///< the state in a sentence
  std::vector<std::pair<std::string, std::string>> values;  ///< key -> value, in order
};

/// The report of a watcher in `state` with `model` in use (null: none), `not_watched` scans
/// left out (queue full, no pose), under `settings`.
DiagnosticReport diagnosticReport(const WatchState& state, const CalibrationModel* model,
                                  const WatchSettings& settings, std::size_t not_watched);

/// The bias of `model` at `d_m` with its standard error, as text ("+23.4 +- 0.8 mm"), or why
/// there is none ("outside the fitted range 0.4-3.1 m").
std::string biasText(const CalibrationModel& model, double d_m);

/// Appends the model's bias at 1, 2 and 3 m ("bias at 1 m" -> biasText), as every mode's
/// /diagnostics status carries it.
void addBiasValues(const CalibrationModel& model,
                   std::vector<std::pair<std::string, std::string>>& values);

}  // namespace lidarcal::watch
