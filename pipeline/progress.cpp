#include "pipeline/progress.hpp"

#include <cstdio>
#include <unistd.h>

namespace lidarcal::pipeline {
namespace {
bool g_quiet = false;
}

void setQuiet(bool q) { g_quiet = q; }
bool quiet() { return g_quiet; }

Progress::Progress(std::string label, std::size_t total, bool enabled)
    : label_(std::move(label)), total_(total), enabled_(enabled && !g_quiet && ::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

Progress::~Progress() {
  if (enabled_ && !finished_) std::fputc('\n', stderr);
}

void Progress::update(std::size_t done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(200) && done < total_) return;
  last_draw_ = now;
  draw(done, false);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  draw(total_, true);
  finished_ = true;
}

void Progress::draw(std::size_t done, bool final) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double frac = total_ ? static_cast<double>(done) / static_cast<double>(total_) : 1.0;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(frac * kWidth);
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = '\0';
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  const double left = rate > 0 ? static_cast<double>(total_ - done) / rate : 0.0;
  if (final)
    std::fprintf(stderr, "\r%s [%s] %zu/%zu in %.1f s%20s\n", label_.c_str(), bar, done, total_, elapsed, "");
  else
    std::fprintf(stderr, "\r%s [%s] %zu/%zu %.1f/s, %.0f s left   ", label_.c_str(), bar, done, total_, rate, left);
  std::fflush(stderr);
}

}  // namespace lidarcal::pipeline
