// SPDX-License-Identifier: BSD-3-Clause
#include "watch/live_watcher.hpp"

#include <utility>

namespace lidarcal::watch {

LiveWatcher::LiveWatcher(const WatchSettings& settings,
                         std::shared_ptr<const CalibrationModel> model, std::size_t queue_scans)
    : capacity_(queue_scans) {
  WatchSink sink;
  // The sink runs on the worker, inside observe(): it fills the worker's own lists.
  sink.check = [this](const CheckEvent& e) { pending_checks_.push_back(e); };
  sink.refit = [this](const RefitEvent& e) { pending_refits_.push_back(e); };
  engine_ = std::make_unique<Engine>(settings, std::move(model), FitExecution::background,
                                     std::move(sink));
  model_ = engine_->model();
  state_ = engine_->state();
  version_ = state_.model_version;
  worker_ = std::thread([this] { run(); });
}

LiveWatcher::~LiveWatcher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  worker_.join();
}

bool LiveWatcher::offer(io::RawScan scan) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= capacity_) {
      ++dropped_;
      return false;
    }
    queue_.push_back(std::move(scan));
  }
  wake_.notify_one();
  return true;
}

void LiveWatcher::run() {
  for (;;) {
    io::RawScan scan;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      scan = std::move(queue_.front());
      queue_.pop_front();
    }
    engine_->observe(scan);  // detection here, fits on the engine's own thread
    std::lock_guard<std::mutex> lock(mutex_);
    model_ = engine_->model();
    version_ = engine_->state().model_version;
    state_ = engine_->state();
    for (auto& e : pending_checks_) checks_.push_back(std::move(e));
    for (auto& e : pending_refits_) refits_.push_back(std::move(e));
    pending_checks_.clear();
    pending_refits_.clear();
  }
}

std::shared_ptr<const CalibrationModel> LiveWatcher::model() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return model_;
}

std::uint64_t LiveWatcher::modelVersion() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return version_;
}

WatchState LiveWatcher::state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_;
}

std::size_t LiveWatcher::dropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}

std::vector<CheckEvent> LiveWatcher::takeChecks() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(checks_, {});
}

std::vector<RefitEvent> LiveWatcher::takeRefits() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(refits_, {});
}

}  // namespace lidarcal::watch
