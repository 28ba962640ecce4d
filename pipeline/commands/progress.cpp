// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/commands/progress.hpp"

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lidarcal::pipeline {
namespace {
bool g_quiet = false;

bool drawable(bool enabled) { return enabled && !g_quiet && ::isatty(STDERR_FILENO) == 1; }

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// "42 s", "3 min 20 s", "2 h 05 min".
std::string duration(double s) {
  char buf[48];
  if (!(s >= 0.0)) s = 0.0;
  if (s < 60.0)
    std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 3600.0)
    std::snprintf(buf, sizeof buf, "%.0f min %02.0f s", std::floor(s / 60.0), std::fmod(s, 60.0));
  else
    std::snprintf(buf, sizeof buf, "%.0f h %02.0f min", std::floor(s / 3600.0),
                  std::floor(std::fmod(s, 3600.0) / 60.0));
  return buf;
}

}  // namespace

void setQuiet(bool q) { g_quiet = q; }
bool quiet() { return g_quiet; }

std::string progressText(const std::string& label, std::size_t done, std::size_t total,
                         double elapsed_s, bool final) {
  char buf[256];
  if (!(elapsed_s >= 0.0)) elapsed_s = 0.0;
  if (total == 0) {
    // Unknown amount of work: what was counted, if anything, and the time spent.
    const std::string count = done ? std::to_string(done) + " " : std::string();
    std::snprintf(buf, sizeof buf, "%s %s%s %.1f s", label.c_str(), count.c_str(),
                  final ? "done in" : "...", elapsed_s);
    return buf;
  }
  done = std::min(done, total);
  constexpr int kWidth = 30;
  const double frac = static_cast<double>(done) / static_cast<double>(total);
  const int filled = static_cast<int>(frac * kWidth);
  std::string bar(static_cast<std::size_t>(kWidth), '.');
  std::fill(bar.begin(), bar.begin() + filled, '#');
  if (final) {
    std::snprintf(buf, sizeof buf, "%s [%s] %zu/%zu in %.1f s", label.c_str(), bar.c_str(), done,
                  total, elapsed_s);
    return buf;
  }
  const double rate = elapsed_s > 0.0 ? static_cast<double>(done) / elapsed_s : 0.0;
  const std::string left =
      rate > 0.0 ? duration(static_cast<double>(total - done) / rate) + " left" : "starting";
  std::snprintf(buf, sizeof buf, "%s [%s] %zu/%zu %.1f/s, %s", label.c_str(), bar.c_str(), done,
                total, rate, left.c_str());
  return buf;
}

Progress::Progress(std::string label, std::size_t total, bool enabled)
    : label_(std::move(label)),
      total_(total),
      enabled_(drawable(enabled)),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() {
  if (enabled_ && !finished_) std::fputc('\n', stderr);
}

void Progress::update(std::size_t done) { update(done, total_); }

void Progress::update(std::size_t done, std::size_t total) {
  done_ = done;
  total_ = total;
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(200) && (total_ == 0 || done < total_)) return;
  last_draw_ = now;
  draw(false);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  if (total_ > 0) done_ = total_;
  draw(true);
  finished_ = true;
}

void Progress::draw(bool final) {
  // Padding clears what a longer previous line left behind.
  std::fprintf(stderr, "\r%s%12s%s",
               progressText(label_, done_, total_, secondsSince(start_), final).c_str(), "",
               final ? "\n" : "");
  std::fflush(stderr);
}

Activity::Activity(std::string label, bool enabled)
    : label_(std::move(label)),
      enabled_(drawable(enabled)),
      start_(std::chrono::steady_clock::now()) {
  if (!enabled_) return;
  thread_ = std::thread([this] {
    std::unique_lock<std::mutex> lock(mutex_);
    do {
      std::fprintf(stderr, "\r%s%12s",
                   progressText(label_, 0, 0, secondsSince(start_), false).c_str(), "");
      std::fflush(stderr);
    } while (!wake_.wait_for(lock, std::chrono::seconds(1), [this] { return stop_; }));
  });
}

Activity::~Activity() { finish(); }

void Activity::finish() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
  std::fprintf(stderr, "\r%s%12s\n", progressText(label_, 0, 0, secondsSince(start_), true).c_str(),
               "");
  std::fflush(stderr);
}

void StageBars::operator()(const std::string& stage, std::size_t done, std::size_t total) {
  if (!bar_ || stage != stage_) {
    finish();
    stage_ = stage;
    bar_ = std::make_unique<Progress>(stage, total);
  }
  bar_->update(done, total);
}

void StageBars::finish() {
  if (bar_) bar_->finish();
  bar_.reset();
}

}  // namespace lidarcal::pipeline
