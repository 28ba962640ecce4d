// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What lidarcal_ros2_node does with each scan and beside the scans, by mode (parameter `mode`):
//
// - apply: ros2::LiveCorrector on each scan; every diagnostics_period an OK entry on /diagnostics
//   (the model corrected with, the counts). No pose input, no watcher.
// - watch, learn: ros2::WatchedCorrector on each scan (corrected with the watcher's model in use,
//   the raw readings offered to the watcher with the scan frame's pose from ros2::PoseInput);
//   every diagnostics_period the watcher's state on /diagnostics (OK, WARN, ERROR); each alarm
//   logged at warn level with its evidence; in learn mode each switch logged with both models and
//   why, and each refit's candidate published as JSON on candidate_topic (latched) and written
//   atomically to candidate_file when set.
//
// A scan without a pose is corrected but not watched, counted and warned about (at most once per
// 5 s); a pose that cannot be one is dropped, counted and warned about the same way. Nothing here
// throws on what arrives on the wire, and nothing prints: the log lines go to the caller's sink.

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "common/calibration_model.hpp"
#include "ros2/live_corrector.hpp"
#include "ros2/node_args.hpp"
#include "ros2/node_messages.hpp"
#include "ros2/node_outputs.hpp"
#include "ros2/pose_input.hpp"
#include "ros2/ros_participant.hpp"
#include "ros2/warning_limiter.hpp"
#include "ros2/watched_corrector.hpp"

struct sensor_msgs_msg_dds__LaserScan_;

namespace lidarcal::ros2 {

/// Where the scan path's log lines go: the node prints each and puts it on /rosout.
using LogSink =
    std::function<void(LogLevel level, const std::string& text, const LogOrigin& origin)>;

/// What the scan path starts from.
struct ScanPathSetup {
  /// the model given (null only in mode learn without one)
  std::shared_ptr<const CalibrationModel> model;
  LiveSettings live;  ///< how to correct: model file, input topic, inversion, outside, checks
};

class NodeScanPath {
 public:
  /// The path for `params.mode` on `participant` (which must outlive it). Throws InputError when
  /// the watcher cannot check the model given (no alpha_covariance), std::runtime_error when
  /// Cyclone refuses a reader or writer.
  NodeScanPath(RosParticipant& participant, const NodeParameters& params,
               const ScanPathSetup& setup, LogSink log);

  /// One received scan: corrected in place (and offered to the watcher); the verdict as
  /// LiveCorrector::process, whose message() and dropReason() corrector() gives. `now_s`: a
  /// monotonic clock, seconds (for the rate limit of warnings).
  ScanVerdict process(sensor_msgs_msg_dds__LaserScan_& scan, double now_s);
  /// Between scans: poses taken in, the watcher's checks and refits logged (candidates
  /// published), /diagnostics when due (`now_s` as for process()).
  void tick(double now_s);

  const LiveCorrector& corrector() const;
  /// The watcher's counts for the summary at exit ("" in apply mode).
  std::string watchSummary() const;

 private:
  void pollPoses(double now_s);
  void logChecks();
  void logRefits();
  std::string publishCandidate(const CalibrationModel& candidate);
  void warn(const std::string& kind, const std::string& text, double now_s);
  DiagnosticEntry diagnostics() const;

  NodeParameters params_;
  LogSink log_;
  std::string topic_;        // the input topic, resolved
  std::string hardware_id_;  // the sensor's name (else the scans' frame_id)
  ScanPathSetup setup_;
  std::optional<LiveCorrector> apply_;         // mode apply
  std::unique_ptr<WatchedCorrector> watched_;  // modes watch and learn
  std::unique_ptr<PoseInput> poses_;
  std::unique_ptr<TextPublisher> candidate_;  // mode learn
  std::string candidate_topic_;
  DiagnosticsPublisher diagnostics_;
  WarningLimiter warnings_;
  double next_diagnostics_s_ = 0.0;
  bool mount_warned_ = false;
};

}  // namespace lidarcal::ros2
