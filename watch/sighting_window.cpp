// SPDX-License-Identifier: BSD-3-Clause
#include "watch/sighting_window.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace lidarcal::watch {

SightingWindow::SightingWindow(std::size_t capacity) : capacity_(capacity) {
  if (capacity_ == 0) throw std::invalid_argument("SightingWindow: capacity must be >= 1");
}

void SightingWindow::push(WatchedScan scan) {
  if (!scans_.empty() && scan.index <= scans_.back().index)
    throw std::invalid_argument("SightingWindow::push: scan indices must increase");
  sightings_ += scan.poles.size();
  scans_.push_back(std::move(scan));
  while (scans_.size() > capacity_) {
    sightings_ -= scans_.front().poles.size();
    scans_.pop_front();
  }
}

void SightingWindow::rename(const std::vector<std::pair<PoleId, PoleId>>& merged) {
  for (const auto& [from, into] : merged)
    for (auto& s : scans_)
      for (auto& p : s.poles)
        if (p.pole == from) p.pole = into;
}

const WatchedScan* SightingWindow::find(std::size_t index) const {
  if (scans_.empty() || index < scans_.front().index || index > scans_.back().index) return nullptr;
  // Indices increase but may skip (scans the watcher did not keep): binary search.
  const auto it = std::lower_bound(scans_.begin(), scans_.end(), index,
                                   [](const WatchedScan& s, std::size_t i) { return s.index < i; });
  return it != scans_.end() && it->index == index ? &*it : nullptr;
}

namespace {

/// The scans of [from, to] held in `scans`.
std::pair<std::deque<WatchedScan>::const_iterator, std::deque<WatchedScan>::const_iterator> span(
    const std::deque<WatchedScan>& scans, std::size_t from, std::size_t to) {
  const auto lo = std::lower_bound(scans.begin(), scans.end(), from,
                                   [](const WatchedScan& s, std::size_t i) { return s.index < i; });
  const auto hi = std::upper_bound(lo, scans.end(), to,
                                   [](std::size_t i, const WatchedScan& s) { return i < s.index; });
  return {lo, hi};
}

/// Landmark number (1, 2, ... by first sighting) of each pole seen often enough in the span.
template <class It>
std::map<PoleId, int> numberPoles(It begin, It end, std::size_t min_sightings) {
  std::map<PoleId, std::size_t> count;
  std::vector<PoleId> order;
  for (It s = begin; s != end; ++s)
    for (const auto& p : s->poles)
      if (count[p.pole]++ == 0) order.push_back(p.pole);
  std::map<PoleId, int> id;
  for (PoleId pole : order)
    if (count[pole] >= min_sightings) id.emplace(pole, static_cast<int>(id.size()) + 1);
  return id;
}

}  // namespace

std::size_t SightingWindow::polesIn(std::size_t from, std::size_t to,
                                    const SpanRules& rules) const {
  const auto [lo, hi] = span(scans_, from, to);
  return numberPoles(lo, hi, rules.min_sightings).size();
}

LandmarkObservations SightingWindow::observations(std::size_t from, std::size_t to,
                                                  const SpanRules& rules) const {
  const auto [lo, hi] = span(scans_, from, to);
  const std::map<PoleId, int> id = numberPoles(lo, hi, rules.min_sightings);
  LandmarkObservations obs;
  obs.landmark_radius_m = rules.landmark_radius_m;
  obs.range_min_m = lo == hi ? 0.0 : lo->range_min_m;
  obs.range_max_m = lo == hi ? 1e9 : lo->range_max_m;
  for (auto s = lo; s != hi; ++s) {
    const std::size_t stop = obs.commanded.size();
    obs.commanded.push_back(s->pose);
    obs.range_min_m = std::min(obs.range_min_m, s->range_min_m);
    obs.range_max_m = std::max(obs.range_max_m, s->range_max_m);
    const std::size_t first = obs.sightings.size();
    for (const auto& p : s->poles) {
      const auto it = id.find(p.pole);
      if (it == id.end()) continue;
      obs.sightings.push_back(
          Sighting{stop, stop, it->second, p.bearing_rad, p.centre_range_m, p.radius_m, p.beams});
    }
    // Within a scan by landmark number, as the sequence pipeline orders them.
    std::stable_sort(obs.sightings.begin() + static_cast<long>(first), obs.sightings.end(),
                     [](const Sighting& a, const Sighting& b) { return a.landmark < b.landmark; });
  }
  return obs;
}

}  // namespace lidarcal::watch
