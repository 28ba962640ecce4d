// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Runs the trials of many cells on a pool of threads. Every trial's seed and layout depend only
// on (study seed, cell, trial) and results are stored by index, so the output is the same
// whatever the thread count or scheduling. Stoppable between trials through a flag. A study can
// also be cut into shards, disjoint slices of its trials run by separate processes (a batch
// engine's array tasks) and merged afterwards into the same results.

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "studies/trial.hpp"

namespace lidarcal::studies {

struct RunOptions {
  int threads = 1;            ///< worker threads (>= 1)
  std::size_t trials = 1000;  ///< trials per cell
  /// the first this many trials of each cell also run the joint refinement
  std::size_t joint_trials = 200;
  std::uint64_t seed = 1;  ///< study seed
  /// Shards: run only slice `shard_index` (0-based) of `shard_count` disjoint slices of the trials
  /// (shardTrials); the other trials' results stay default. Default: one slice, every trial.
  std::size_t shard_index = 0;
  std::size_t shard_count = 1;  ///< number of slices (>= 1)
  /// when set to true, workers stop after their current trial
  const std::atomic<bool>* stop = nullptr;
  /// Called from the calling thread about five times a second and once at the end: trials done,
  /// total.
  std::function<void(std::size_t done, std::size_t total)> on_progress;
  void validate() const;  ///< throws std::invalid_argument
};

/// One trial of a study: its cell (index into the study's cells) and its number in the cell.
struct TrialIndex {
  std::size_t cell = 0;   ///< index of the cell
  std::size_t trial = 0;  ///< trial number in the cell, 0-based
};

/// The trials of slice options.shard_index of options.shard_count, in the order they run. The
/// trials with the (slow) joint refinement are numbered cell by cell, and so are the others; a
/// slice takes every shard_count-th of each, so the slices get equal numbers of both (within one)
/// and an even share of every cell, and take about the same time. The slices 0 ... N - 1 hold
/// every trial exactly once. Depends on (cells, trials, joint_trials, shard) only.
std::vector<TrialIndex> shardTrials(std::size_t cells, const RunOptions& options);

struct StudyRun {
  std::vector<std::vector<TrialResult>> results;  ///< results[cell][trial]
  bool interrupted = false;  ///< stopped through RunOptions::stop: results are incomplete
};

/// Runs every trial of every cell (of the slice options.shard_index). An exception in a trial (e.g.
/// a layout that cannot be placed) stops the run and is rethrown here.
StudyRun runCells(const TrialConfig& config, const std::vector<Cell>& cells,
                  const RunOptions& options);

}  // namespace lidarcal::studies
