#pragma once
// Runs the trials of many cells on a pool of threads. Every trial's seed and layout depend only
// on (study seed, cell, trial) and results are stored by index, so the output is the same
// whatever the thread count or scheduling. Stoppable between trials through a flag.

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "studies/trial.hpp"

namespace lidarcal::studies {

struct RunOptions {
  int threads = 1;                 ///< worker threads (>= 1)
  std::size_t trials = 1000;       ///< trials per cell
  std::size_t joint_trials = 200;  ///< the first this many trials of each cell also run the joint refinement
  std::uint64_t seed = 1;          ///< study seed
  const std::atomic<bool>* stop = nullptr;  ///< when set to true, workers stop after their current trial
  /// Called from the calling thread about five times a second and once at the end: trials done, total.
  std::function<void(std::size_t done, std::size_t total)> on_progress;
  void validate() const;           ///< throws std::invalid_argument
};

struct StudyRun {
  std::vector<std::vector<TrialResult>> results;  ///< results[cell][trial]
  bool interrupted = false;        ///< stopped through RunOptions::stop: results are incomplete
};

/// Runs every trial of every cell. An exception in a trial (e.g. a layout that cannot be
/// placed) stops the run and is rethrown here.
StudyRun runCells(const TrialConfig& config, const std::vector<Cell>& cells, const RunOptions& options);

}  // namespace lidarcal::studies
