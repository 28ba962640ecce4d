// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Progress on stderr for long work: a bar with rate and time left, redrawn at most 5 times a
// second, only when stderr is a terminal (logs stay clean) and not silenced with --quiet.
// Stages whose work cannot be counted show their name and the time spent (Activity).

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace lidarcal::pipeline {

/// The text of one progress line (no carriage return, no newline): `label [####....] done/total
/// rate, time left`, or with `final` the count and the time taken. `done` beyond `total` is
/// shown as `total` (a count never runs past its total, the time left never goes negative);
/// `total` 0 means the amount of work is unknown: the line shows the count (if any) and the
/// time spent. Pure, for tests.
std::string progressText(const std::string& label, std::size_t done, std::size_t total,
                         double elapsed_s, bool final);

class Progress {
 public:
  /// `total` 0: unknown amount of work (the line counts without a bar).
  Progress(std::string label, std::size_t total, bool enabled = true);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Sets the number of units done.
  void update(std::size_t done);
  /// Sets the number of units done and the total (a stage that learns it needs a second pass).
  void update(std::size_t done, std::size_t total);
  /// Draws the final state and ends the line.
  void finish();

 private:
  void draw(bool final);
  std::string label_;
  std::size_t done_ = 0, total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

/// A stage that cannot count its work (one long library call): its name and the seconds spent,
/// redrawn once a second from a helper thread until finish() or destruction.
class Activity {
 public:
  explicit Activity(std::string label, bool enabled = true);
  ~Activity();
  Activity(const Activity&) = delete;
  Activity& operator=(const Activity&) = delete;
  void finish();

 private:
  std::string label_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

/// Progress of a run of named stages (detect, joint refinement, ...): one line per stage, a new
/// line when the stage name changes. Fits calibration::CalibrationConfig::progress and the
/// detector's scan callback.
class StageBars {
 public:
  StageBars() = default;
  void operator()(const std::string& stage, std::size_t done, std::size_t total);
  /// Ends the current stage's line.
  void finish();

 private:
  std::string stage_;
  std::unique_ptr<Progress> bar_;
};

/// Global switch set by --quiet (the only process-wide setting; read by Progress).
void setQuiet(bool quiet);
bool quiet();

}  // namespace lidarcal::pipeline
