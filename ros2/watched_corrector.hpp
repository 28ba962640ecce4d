// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The node's scan path in modes watch and learn, without DDS. Each scan is corrected at once with
// the field watcher's model in use (watch::LiveWatcher::model(), through ros2::LiveCorrector), and
// a copy of its raw readings, with the scan frame's pose at its stamp, is offered to the watcher,
// which never blocks: correction never waits for detection or a fit. When the watcher switches
// models (learn mode), the correction follows from the next scan on. A scan without a pose, or
// one offered while the watcher's queue is full, is corrected but not watched (counted, and the
// reason kept for a warning). What the node logs and puts on /diagnostics is made here as text
// and plain structs (ros2/node_messages.hpp); ros2/node_watch.hpp puts them on the wire.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "common/calibration_model.hpp"
#include "ros2/live_corrector.hpp"
#include "ros2/live_poses.hpp"
#include "ros2/node_args.hpp"
#include "ros2/node_messages.hpp"
#include "watch/events.hpp"
#include "watch/live_watcher.hpp"
#include "watch/watch_settings.hpp"

namespace lidarcal::ros2 {

/// Scans the watcher may hold waiting (6.4 s of a 10 Hz sensor); more are corrected, not watched.
inline constexpr std::size_t kWatchQueueScans = 64;

/// The watcher's settings from the node's parameters: watch::defaultWatchSettings() with the mode,
/// the false-alarm rate, the check spacing and the poles' radius (for the checks and the
/// detector) the parameters give.
watch::WatchSettings watchSettingsFor(const NodeParameters& p);

class WatchedCorrector {
 public:
  /// `model`: the model given (null in learn mode without one: scans pass uncorrected until one
  /// is learnt); `live`: how to correct. Throws std::invalid_argument as watch::LiveWatcher does
  /// (a model the watcher cannot check), and what pipeline::modelCorrector throws.
  WatchedCorrector(const watch::WatchSettings& settings,
                   std::shared_ptr<const CalibrationModel> model, const LiveSettings& live,
                   std::size_t queue_scans = kWatchQueueScans);

  /// Corrects `scan` (LiveCorrector::process) with the model in use, after taking up a switch.
  /// A published scan goes to the watcher too when `pose` has one: its raw readings as received
  /// (copied before the correction), that pose, `stamp` and its range limits.
  ScanVerdict process(ScanFields& scan, const RosTime& stamp, const PoseLookup& pose);

  const LiveCorrector& corrector() const { return live_; }
  watch::LiveWatcher& watcher() { return watcher_; }
  const watch::LiveWatcher& watcher() const { return watcher_; }
  const watch::WatchSettings& settings() const { return settings_; }
  /// The version of the model the scans are corrected with (0: none yet).
  std::uint64_t correctingVersion() const { return correcting_version_; }
  /// Why the last published scan was not watched ("" when it was offered).
  const std::string& notWatched() const { return not_watched_; }
  /// Published scans not watched for want of a pose.
  std::size_t withoutPose() const { return without_pose_; }
  /// A switch the correction could not follow (the learnt model cannot be inverted as set), said
  /// once at the scan that met it; "" otherwise.
  const std::string& switchProblem() const { return switch_problem_; }

 private:
  void followSwitch();

  watch::WatchSettings settings_;
  LiveSettings live_settings_;
  watch::LiveWatcher watcher_;
  LiveCorrector live_;
  std::uint64_t seen_version_ = 0;        // the watcher's model version last taken up
  std::uint64_t correcting_version_ = 0;  // the version the scans are corrected with
  std::size_t without_pose_ = 0;
  std::string not_watched_, switch_problem_;
};

/// The /diagnostics entry in watch and learn modes: watch::diagnosticReport (level mapped
/// OK/WARN/ERROR), then the correction's counts. Named "lidarcal: range model of TOPIC".
DiagnosticEntry watchDiagnostics(const WatchedCorrector& w, const std::string& topic,
                                 const std::string& hardware_id);

/// The /diagnostics entry in apply mode: OK, the model corrected with, its bias at 1, 2 and 3 m,
/// and the correction's counts.
DiagnosticEntry applyDiagnostics(const LiveCorrector& c, const CalibrationModel& model,
                                 const std::string& model_file, const std::string& topic,
                                 const std::string& hardware_id);

/// The log line of a switch (RefitEvent adopted): the model's number, both models' bias at 1, 2
/// and 3 m with their standard errors, and why.
std::string switchLine(const watch::RefitEvent& e);
/// The log line of a refit's candidate: its stretch, adopted or not and why, and where it went
/// (`published`: the topic and file, as a phrase).
std::string candidateLine(const watch::RefitEvent& e, const std::string& published);

}  // namespace lidarcal::ros2
