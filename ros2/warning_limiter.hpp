// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Rate-limited warnings for a live node: a warning of one kind is let through at most once per
// `period_s`; the ones held back in between are counted and reported with the next one let
// through. The caller passes the time (seconds on a monotonic clock), so the rule is testable.

#include <cstddef>
#include <map>
#include <string>

namespace lidarcal::ros2 {

class WarningLimiter {
 public:
  /// period_s: shortest time between two warnings of one kind, seconds (default 5).
  explicit WarningLimiter(double period_s = 5.0) : period_s_(period_s) {}

  /// The text to print for a warning of `kind` at `now_s`, or empty when it is held back. The
  /// text says how many of that kind were held back since the last one printed.
  std::string offer(const std::string& kind, const std::string& text, double now_s) {
    Kind& k = kinds_[kind];
    if (k.printed && now_s - k.last_s < period_s_) {
      ++k.held;
      return {};
    }
    std::string out = text;
    if (k.held > 0) out += " (" + std::to_string(k.held) + " more like it since the last warning)";
    k = {true, now_s, 0};
    return out;
  }

 private:
  struct Kind {
    bool printed = false;  // one was printed already
    double last_s = 0.0;   // when the last one was printed
    std::size_t held = 0;  // held back since
  };
  double period_s_;
  std::map<std::string, Kind> kinds_;
};

}  // namespace lidarcal::ros2
