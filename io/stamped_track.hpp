// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Samples of one quantity over time (a frame's transform, the wheels' angles), looked up at a
// stamp: interpolated between the samples around it by `Lerp`, the nearest end sample within a
// hold time outside the recorded span, nothing further out. Stamps may arrive in any order; the
// samples are sorted on first lookup.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <optional>
#include <utility>
#include <vector>

namespace lidarcal::io {

/// `Lerp` is a type with `static Value lerp(const Value& a, const Value& b, double u)`, u in [0,
/// 1].
template <typename Value, typename Lerp>
class StampedTrack {
 public:
  /// Adds a sample; stamps may come in any order (sorted on first lookup).
  void add(double stamp_s, const Value& v) {
    if (!samples_.empty() && stamp_s < samples_.back().first) sorted_ = false;
    samples_.emplace_back(stamp_s, v);
  }
  bool empty() const { return samples_.empty(); }
  std::size_t size() const { return samples_.size(); }
  /// Stamp range [first, last], seconds. Undefined when empty.
  std::pair<double, double> span() const {
    sort();
    return {samples_.front().first, samples_.back().first};
  }
  /// The value at `stamp_s`: interpolated between the samples around it; the nearest end
  /// sample within `hold_s` outside the span; nothing further out.
  std::optional<Value> at(double stamp_s, double hold_s) const {
    if (samples_.empty() || !std::isfinite(stamp_s)) return std::nullopt;
    sort();
    const auto after = std::lower_bound(samples_.begin(), samples_.end(), stamp_s,
                                        [](const auto& s, double t) { return s.first < t; });
    if (after == samples_.begin())
      return stamp_s >= after->first - hold_s ? std::optional<Value>(after->second) : std::nullopt;
    if (after == samples_.end()) {
      const auto& last = samples_.back();
      return stamp_s <= last.first + hold_s ? std::optional<Value>(last.second) : std::nullopt;
    }
    const auto& [t1, b] = *after;
    const auto& [t0, a] = *std::prev(after);
    const double u = t1 > t0 ? (stamp_s - t0) / (t1 - t0) : 1.0;
    return Lerp::lerp(a, b, u);
  }
  /// Forgets the samples stamped more than `window_s` before the newest one, keeping the last of
  /// them (so a stamp inside the window still interpolates), and then all but the newest
  /// `max_samples` (at least 2 kept). For a live stream, whose past must not grow without bound.
  void keepWithin(double window_s, std::size_t max_samples) {
    if (samples_.size() < 2) return;
    sort();
    const double oldest_kept = samples_.back().first - window_s;
    auto first = std::lower_bound(samples_.begin(), samples_.end(), oldest_kept,
                                  [](const auto& s, double t) { return s.first < t; });
    if (first != samples_.begin()) --first;  // the last sample before the window
    const std::size_t keep = std::max<std::size_t>(max_samples, 2);
    const auto by_count =
        samples_.end() - static_cast<std::ptrdiff_t>(std::min(keep, samples_.size()));
    samples_.erase(samples_.begin(), std::max(first, by_count));
  }

 private:
  void sort() const {
    if (sorted_) return;
    std::stable_sort(samples_.begin(), samples_.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    sorted_ = true;
  }
  mutable std::vector<std::pair<double, Value>> samples_;
  mutable bool sorted_ = true;
};

}  // namespace lidarcal::io
