#pragma once
// Progress on stderr for long work: a bar with rate and time left, redrawn at most 5 times a
// second, only when stderr is a terminal (logs stay clean) and not silenced with --quiet.

#include <chrono>
#include <cstddef>
#include <string>

namespace lidarcal::pipeline {

class Progress {
 public:
  Progress(std::string label, std::size_t total, bool enabled = true);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Sets the number of units done.
  void update(std::size_t done);
  /// Draws the final state and ends the line.
  void finish();

 private:
  void draw(std::size_t done, bool final);
  std::string label_;
  std::size_t total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

/// Global switch set by --quiet (the only process-wide setting; read by Progress).
void setQuiet(bool quiet);
bool quiet();

}  // namespace lidarcal::pipeline
