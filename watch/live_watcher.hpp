// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The field watcher beside a live correction loop (the ROS 1 and ROS 2 nodes): the node corrects
// each scan with model() at once and hands a copy of its raw readings to offer(), which never
// blocks; a thread of the watcher's own runs the engine on them (detection, tracking) and the
// engine's fits run on a further thread (FitExecution::background). So correction never waits for
// detection or a fit; when the watcher falls behind, scans are left out of watching (counted),
// never out of correction. The node reads state() for /diagnostics and takes the events for its
// log.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "watch/engine.hpp"

namespace lidarcal::watch {

class LiveWatcher {
 public:
  /// As Engine's constructor (throws std::invalid_argument the same way). Holds at most
  /// `queue_scans` scans waiting to be watched.
  LiveWatcher(const WatchSettings& settings, std::shared_ptr<const CalibrationModel> model,
              std::size_t queue_scans = 32);
  ~LiveWatcher();
  LiveWatcher(const LiveWatcher&) = delete;
  LiveWatcher& operator=(const LiveWatcher&) = delete;

  /// Hands a scan (raw readings, pose, stamp) to the watcher; false when the queue was full and
  /// the scan is not watched.
  bool offer(io::RawScan scan);

  /// The model to correct with now (null: none yet) and its version (changes at a switch).
  std::shared_ptr<const CalibrationModel> model() const;
  std::uint64_t modelVersion() const;
  /// The state now (a copy).
  WatchState state() const;
  /// Scans not watched because the queue was full.
  std::size_t dropped() const;
  /// The checks and refits decided since the last call, in order.
  std::vector<CheckEvent> takeChecks();
  std::vector<RefitEvent> takeRefits();

 private:
  void run();

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<io::RawScan> queue_;
  std::size_t capacity_;
  std::size_t dropped_ = 0;
  bool stop_ = false;
  std::shared_ptr<const CalibrationModel> model_;
  std::uint64_t version_ = 0;
  WatchState state_;
  std::vector<CheckEvent> checks_;
  std::vector<RefitEvent> refits_;
  std::vector<CheckEvent> pending_checks_;  // the worker's, until handed over under the lock
  std::vector<RefitEvent> pending_refits_;
  std::unique_ptr<Engine> engine_;  // used by the worker only
  std::thread worker_;
};

}  // namespace lidarcal::watch
