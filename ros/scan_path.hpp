// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What lidarcal_node does with each LaserScan, apart from ROS: in watch and learn modes, the raw
// readings go to the field watcher (watch/live_watcher.hpp) with the pose of the scan's frame at
// its stamp, then the ranges are corrected with the model the watcher holds (when it switches,
// the new model's corrector is built on a thread of its own and used from the scan after it is
// ready); in apply mode the ranges are only corrected. The correction is the rule of
// `lidarcal correct IN.bag` (pipeline::correctLaserRanges through a MemoCorrector) in every mode,
// and it never waits for the watcher: offering a scan copies its readings and returns at once.
// No ROS types, so the per-scan cost can be measured without a master (bench/bench_node_watch).

#include <cstddef>
#include <cstdint>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "calibration/filtering.hpp"
#include "common/calibration_model.hpp"
#include "io/bag_scans.hpp"
#include "pipeline/stages/bag_correct.hpp"
#include "ros2/live_poses.hpp"
#include "watch/diagnostics.hpp"
#include "watch/live_watcher.hpp"

namespace lidarcal::ros1 {

/// How the path corrects and watches.
struct ScanPathSettings {
  std::string model_file;  ///< the model's file, for messages ("" in learn mode without one)
  /// the inversion, as ~inversion
  calibration::InversionMethod method = calibration::InversionMethod::ls;
  /// readings outside the fitted range, as ~outside
  calibration::Outside outside = calibration::kDefaultOutside;
  /// the watcher's settings; unset: apply mode (no watcher, no poses, no threads)
  std::optional<watch::WatchSettings> watch;
  /// where the poses come from and how long they are kept (watch and learn modes)
  ros2::LivePoseSettings poses;
  std::size_t queue_scans = 32;  ///< scans waiting for the watcher at most; more are not watched
  /// added to the caller's nice value for the watcher's threads (detection, fits), so that the
  /// correction comes first on a busy CPU; 0: the caller's priority. Default 10
  int watcher_nice = 10;
};

/// What became of one scan.
struct ScanOutcome {
  bool corrected = false;  ///< its ranges went through a model (false: no model in use yet)
  bool watched = false;    ///< handed to the watcher
  /// why it was not watched in watch or learn mode ("" when it was, or in apply mode)
  std::string not_watched;
  /// set at the first scan corrected with the model the watcher switched to: its version
  std::optional<std::uint64_t> switched_to;
  /// set (with switched_to) when that model cannot correct: the previous one stays, this says why
  std::string switch_error;
  std::vector<watch::CheckEvent> checks;  ///< checks decided since the previous scan
  std::vector<watch::RefitEvent> refits;  ///< refits decided since the previous scan
};

/// Counts over the node's life.
struct ScanPathStats {
  pipeline::CorrectionStats correction;  ///< scans received and what became of their returns
  std::size_t uncorrected_scans = 0;     ///< passed on as received (no model in use yet)
  std::size_t without_pose = 0;          ///< not watched: no pose at their stamp
  std::size_t malformed = 0;             ///< not watched: no beams, or angles or limits not finite
};

class ScanPath {
 public:
  /// `model`: the model to correct with (null only in learn mode). Throws std::invalid_argument
  /// when the watcher cannot check it (no alpha_covariance, no usable fit) and the errors of
  /// pipeline::modelCorrector when it cannot correct.
  ScanPath(const ScanPathSettings& settings, std::shared_ptr<const CalibrationModel> model);
  ~ScanPath();
  ScanPath(const ScanPath&) = delete;
  ScanPath& operator=(const ScanPath&) = delete;

  /// One received scan: `msg` its fields (views into the message), `frame_id` its header's frame,
  /// `ranges` a copy of its ranges, corrected in place.
  ScanOutcome process(const io::LaserScanView& msg, const std::string& frame_id,
                      std::vector<float>& ranges);

  /// The poses (odometry, tf) the node receives go here; null in apply mode.
  ros2::LivePoses* poses() { return poses_ ? &*poses_ : nullptr; }
  /// The version of the model corrected with now (0: none yet; 1: the one given; +1 a switch).
  std::uint64_t modelVersion() const { return version_; }
  const ScanPathStats& stats() const { return stats_; }
  /// The watcher (its state, counts); null in apply mode.
  const watch::LiveWatcher* watcher() const { return watcher_.get(); }

  /// The /diagnostics content now: the watcher's (watch::diagnosticReport) in watch and learn
  /// modes; in apply mode OK with the model and the counts.
  watch::DiagnosticReport report() const;

 private:
  void offer(const io::LaserScanView& msg, const std::string& frame_id, ScanOutcome& out);
  void followSwitch(const io::LaserScanView& msg, ScanOutcome& out);

  /// The corrector of a model the watcher switched to, built off the scan path.
  struct PreparedModel {
    std::uint64_t version = 0;
    std::shared_ptr<const CalibrationModel> model;
    std::optional<pipeline::MemoCorrector> correct;  // unset when it cannot correct
    std::string error;                               // why not
  };
  static PreparedModel prepareModel(std::shared_ptr<const CalibrationModel> model,
                                    std::uint64_t version, const ScanPathSettings& settings,
                                    const std::vector<float>& recent);

  ScanPathSettings settings_;
  std::shared_ptr<const CalibrationModel> model_;
  std::uint64_t version_ = 0;       // of model_ (0: none)
  std::uint64_t seen_version_ = 0;  // the watcher's model version last seen
  // remembers the readings seen: a lookup per beam after the first scans
  std::optional<pipeline::MemoCorrector> correct_;
  std::optional<ros2::LivePoses> poses_;
  std::unique_ptr<watch::LiveWatcher> watcher_;
  std::future<PreparedModel> preparing_;  // a switched-to model's corrector being built
  std::thread builder_;                   // ... on this thread
  std::thread retirer_;                   // frees the corrector before a switch
  ScanPathStats stats_;
};

}  // namespace lidarcal::ros1
