// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The settings of the field watcher (engine.hpp): what it does beside correcting, how often it
// checks the range model, the false-alarm rate its alarms keep to, and how it learns a new
// model. Every field has a default a robot can start with.

#include <cstddef>
#include <optional>
#include <string>

#include "detectors/association.hpp"
#include "detectors/scan_detector.hpp"

namespace lidarcal::watch {

/// What the watcher does with the model it is given.
enum class Mode {
  watch,  ///< checks the model and raises alarms; never changes it
  learn,  ///< also refits from the poles passed and switches to a better model
};
const char* toString(Mode m);
/// Parses "watch" or "learn"; false for anything else.
bool parseMode(const std::string& text, Mode& out);

/// What the false-alarm rate is counted against.
enum class Exposure {
  distance,  ///< kilometres travelled (path length of the poses)
  time,      ///< hours of driving (time between scans while the pose moves; needs stamps)
};
const char* toString(Exposure e);

/// The alarm's false-alarm rate: the expected number of alarms per unit of exposure while the
/// sensor still matches the model (false_alarms.hpp).
struct FalseAlarmRate {
  double per_unit = 0.1;               ///< alarms per km or per hour. Default 0.1
  Exposure unit = Exposure::distance;  ///< per km (default) or per hour of driving
};

/// When and on what the model is checked (model_check.hpp).
struct CheckSettings {
  /// Travel between two checks, metres: each check tests the scans since the previous completed
  /// check. Longer spans see more poles from more places (smaller standard errors) but report
  /// later. Default 3.
  double every_m = 3.0;
  /// The most scans one check or refit takes; older ones leave the window (memory stays bounded
  /// whatever the drive's length). Default 1500.
  std::size_t max_scans = 1500;
  /// A pole takes part in a check when seen in at least this many scans of it. Default 8.
  std::size_t min_sightings = 8;
  /// Checks that form a model's baseline before the first test (shift_history.hpp): the
  /// watcher learns how its checks scatter before it judges one. Default 5.
  std::size_t baseline_checks = 5;
  /// Passed checks kept as the record new ones are compared with. Default 50.
  std::size_t record_checks = 50;
  /// With no completed check over this many check spans the state turns WARN (no poles to
  /// check against, or none the fit can use). Default 10.
  double stale_after_spans = 10.0;
  /// Pole radius, metres; unset: estimated from the arcs with the bias (an offset trades off
  /// against it, so a known radius checks the offset far better). Default unset.
  std::optional<double> landmark_radius_m;
  /// Parametric-bootstrap replicas that estimate a check fit's own bias at its stretch's
  /// geometry (model_check.hpp), for the checks tested against zero: a model's baseline, and in
  /// learn mode the checks after its baseline failed. Their shifts are tested with that bias
  /// taken out; the change tests, which cancel a bias all checks share, use the fitted shifts.
  /// 0: none. Default 4.
  int bias_replicas = 4;
};

/// How learn mode refits and when it switches (model_switch.hpp).
struct LearnSettings {
  /// Largest bias order a refit tries; the order is chosen as `calibrate` chooses it (AIC,
  /// parsimonious). Default 4, as `calibrate`.
  int max_order = 4;
  /// A candidate counts as determined when the standard error of its curve stays below this
  /// over the distances compared, metres. Default 0.003.
  double max_standard_error_m = 0.003;
  /// Level of the test that a candidate differs from the active model, over all the refits
  /// after one alarm (refit k is tested at switch_level / (k (k + 1))). Default 0.01.
  double switch_level = 0.01;
  /// The most scans a refit takes (the latest ones since the change). Default 3000.
  std::size_t max_scans = 3000;
};

struct WatchSettings {
  Mode mode = Mode::watch;               ///< watch (default) or learn
  FalseAlarmRate false_alarms;           ///< the alarm's rate
  CheckSettings check;                   ///< checks
  LearnSettings learn;                   ///< refits (learn mode)
  detectors::DetectionConfig detection;  ///< per-scan pole detection
  /// Tracking poles from scan to scan (each scan its own pose); a watcher sets drift_per_m for
  /// continuous motion and forgets landmarks it has left behind (see defaultWatchSettings()).
  detectors::AssociationConfig association;
  /// Threads of the check's and refit's fits (their results do not depend on it). Default 1.
  int threads = 1;
  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// The defaults, with the association set for a robot that never stops: the reach of a track
/// grows with the travel since it was last seen, and poles unseen for the span of a window are
/// forgotten.
WatchSettings defaultWatchSettings();

}  // namespace lidarcal::watch
