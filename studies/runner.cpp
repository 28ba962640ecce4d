// SPDX-License-Identifier: BSD-3-Clause
#include "studies/runner.hpp"

#include <algorithm>
#include <chrono>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace lidarcal::studies {

void RunOptions::validate() const {
  if (threads < 1) throw std::invalid_argument("RunOptions: threads must be >= 1");
  if (trials < 1) throw std::invalid_argument("RunOptions: trials must be >= 1");
  if (shard_count < 1 || shard_index >= shard_count)
    throw std::invalid_argument("RunOptions: shard_index must be below shard_count (>= 1)");
}

namespace {

/// Work order of one slice: trials with the (slow) joint refinement spread evenly among the
/// others, so the rate seen by the progress bar, and its estimate of the time left, stays steady.
/// Which trials: the slow ones are counted cell by cell (cell c's trial t < J is number c J + t)
/// and so are the fast ones (c (T - J) + t - J); slice k takes those whose number is k modulo
/// shard_count. The slices get equal numbers of slow and of fast trials (within one) and an even
/// share of every cell's trials (cells differ in cost).
std::vector<TrialIndex> workOrder(std::size_t cells, const RunOptions& options) {
  const std::size_t T = options.trials, J = std::min(options.joint_trials, options.trials);
  std::vector<TrialIndex> slow, fast;
  for (std::size_t t = 0; t < T; ++t)
    for (std::size_t c = 0; c < cells; ++c) {
      const std::size_t number = t < J ? c * J + t : c * (T - J) + (t - J);
      if (number % options.shard_count == options.shard_index)
        (t < J ? slow : fast).push_back({c, t});
    }
  std::vector<TrialIndex> out;
  out.reserve(slow.size() + fast.size());
  std::size_t i = 0, j = 0;
  while (i < slow.size() || j < fast.size()) {
    // Take from the list that is further behind its share.
    const bool take_slow =
        j >= fast.size() || (i < slow.size() && i * fast.size() <= j * slow.size());
    out.push_back(take_slow ? slow[i++] : fast[j++]);
  }
  return out;
}

}  // namespace

std::vector<TrialIndex> shardTrials(std::size_t cells, const RunOptions& options) {
  options.validate();
  return workOrder(cells, options);
}

StudyRun runCells(const TrialConfig& config, const std::vector<Cell>& cells,
                  const RunOptions& options) {
  config.validate();
  options.validate();
  StudyRun run;
  run.results.assign(cells.size(), std::vector<TrialResult>(options.trials));
  const std::vector<TrialIndex> order = shardTrials(cells.size(), options);
  std::atomic<std::size_t> next{0}, done{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto stopRequested = [&] { return failed.load() || (options.stop && options.stop->load()); };
  auto worker = [&] {
    for (;;) {
      if (stopRequested()) return;
      const std::size_t i = next.fetch_add(1);
      if (i >= order.size()) return;
      const TrialIndex& it = order[i];
      try {
        const Cell& cell = cells[it.cell];
        const auto layout = trialLayout(config, options.seed, it.trial, cell.landmarks);
        run.results[it.cell][it.trial] =
            runTrial(config, cell, layout, trialSeed(options.seed, cell, it.trial),
                     it.trial < options.joint_trials);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        failed = true;
        return;
      }
      ++done;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < options.threads; ++t) pool.emplace_back(worker);
  // The calling thread reports progress until the workers are through.
  auto last = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  while (done.load() < order.size() && !stopRequested()) {
    const auto now = std::chrono::steady_clock::now();
    if (options.on_progress && now - last >= std::chrono::milliseconds(200)) {
      options.on_progress(done.load(), order.size());
      last = now;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
  if (options.on_progress) options.on_progress(done.load(), order.size());
  run.interrupted = done.load() < order.size();
  return run;
}

}  // namespace lidarcal::studies
