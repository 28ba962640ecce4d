// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the field watcher reports: a record of every check and every refit, handed to a sink as
// it happens (the `watch` command keeps them as its timeline; the nodes log them), and its state
// now (the nodes' /diagnostics).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>

#include "calibration/model_comparison.hpp"
#include "common/calibration_model.hpp"
#include "watch/model_check.hpp"
#include "watch/model_switch.hpp"
#include "watch/shift_history.hpp"

namespace lidarcal::watch {

/// The stretch of driving a check or a refit took.
struct Stretch {
  std::size_t first_scan = 0;  ///< index of its first scan
  std::size_t last_scan = 0;   ///< index of its last scan
  double travel_m = 0.0;       ///< travel at its last scan since the watcher started, metres
  double length_m = 0.0;       ///< its own length, metres
  double stamp_s = std::numeric_limits<double>::quiet_NaN();  ///< stamp of its last scan
};

/// Which test a check was decided by (shift_history.hpp).
enum class Test {
  none,      ///< no decision: the check failed, or it checked a model no longer in use
  baseline,  ///< recorded as part of the model's baseline; no test yet
  absolute,  ///< the baseline's mean shift against zero (is this the sensor the model describes?)
  change,    ///< the check against the record of passed checks (has the sensor changed?)
};
const char* toString(Test t);

/// One check and the decision on it.
struct CheckEvent {
  Stretch stretch;             ///< what it tested
  std::size_t decided_at = 0;  ///< the scan at which its result arrived
  ModelCheck check;            ///< the shift (status not ok: no decision)
  Test test = Test::none;      ///< how it was decided
  FTest f;                     ///< the test's statistic and p-value (test absolute or change)
  std::size_t record = 0;      ///< checks in the record it was compared with
  double level = 0.0;          ///< the test's size alpha_k (false_alarms.hpp); 0 without a test
  double exposure = 0.0;       ///< the exposure that level spent, km or h
  bool exceeds = false;        ///< p < level: this test rejects the model in use
  /// The first test to reject the model in use: the alarm (the state stays ERROR until the
  /// model is replaced; later rejections only exceed).
  bool alarm = false;
  std::uint64_t model_version = 0;  ///< the model checked (1 = the one given, +1 per switch)
};

/// One refit (learn mode) and what became of its candidate.
struct RefitEvent {
  Stretch stretch;                                    ///< the raw readings it was fitted to
  std::size_t decided_at = 0;                         ///< the scan at which its result arrived
  std::shared_ptr<const CalibrationModel> candidate;  ///< the refit
  SwitchDecision decision;                            ///< judged against the model in use
  std::shared_ptr<const CalibrationModel> previous;   ///< the model in use before (may be null)
  std::uint64_t model_version = 0;                    ///< the model in use after it
};

/// Receives the records as they are made (either may be empty).
struct WatchSink {
  std::function<void(const CheckEvent&)> check;
  std::function<void(const RefitEvent&)> refit;
};

/// The diagnostic level of the watcher's state.
enum class Health {
  ok,     ///< the last check found the model holds
  warn,   ///< not checked lately (no poles the fit can use), or learning
  error,  ///< the last check rejected the model at the set false-alarm rate
};
const char* toString(Health h);

/// The watcher's state now.
struct WatchState {
  Health level = Health::warn;           ///< OK, WARN or ERROR
  std::string message = "no check yet";  ///< the state in a sentence
  std::uint64_t model_version = 0;       ///< 0: no model in use (learn mode, none given yet)
  bool learning = false;                 ///< a refit is under way (learn mode)
  std::size_t scans = 0;                 ///< scans seen
  std::size_t sightings = 0;             ///< pole sightings in the window
  std::size_t tracks = 0;                ///< tracks held (poles seen lately)
  double travel_m = 0.0;                 ///< travel since the watcher started, metres
  double driving_h = 0.0;                ///< hours of driving since it started (stamps needed)
  std::size_t checks = 0;                ///< tests decided so far (absolute and change)
  std::size_t alarms = 0;                ///< alarms raised (one per model in use at most)
  std::size_t switches = 0;              ///< models switched to
  /// The last check decided (test none: none yet under the model in use).
  CheckEvent last_check;
  /// The model's absolute test (at the end of its baseline): p-value and level; NaN before.
  double absolute_p = std::numeric_limits<double>::quiet_NaN();
  double absolute_level = std::numeric_limits<double>::quiet_NaN();
  /// Travel and driving time since the last completed check, metres and seconds.
  double since_check_m = 0.0, since_check_s = 0.0;
};

}  // namespace lidarcal::watch
