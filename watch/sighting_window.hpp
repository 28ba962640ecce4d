// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The scans the watcher remembers: each scan's pose, time and travel with the poles it saw, in a
// window of bounded length (the oldest scan leaves when a new one comes in beyond capacity), and
// the landmark observations of any span of it, in the form `calibrate` takes.

#include <cstddef>
#include <deque>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "common/landmark_observations.hpp"
#include "common/pose2.hpp"
#include "watch/pole_tracker.hpp"

namespace lidarcal::watch {

/// One scan as the watcher keeps it.
struct WatchedScan {
  std::size_t index = 0;  ///< position in what the watcher was given, 0-based
  double stamp_s = std::numeric_limits<double>::quiet_NaN();  ///< time stamp, s (NaN: none)
  Pose2 pose;                ///< the sensor's pose in the world frame
  double travel_m = 0.0;     ///< path length from the first scan to this one, metres
  double driving_h = 0.0;    ///< hours of driving (time while the pose moves) up to this scan
  double range_min_m = 0.0;  ///< the scan's reporting window, metres
  double range_max_m = std::numeric_limits<double>::infinity();  ///< metres
  std::vector<PoleSighting> poles;                               ///< the poles it saw
};

/// Which poles of a span enter its observations.
struct SpanRules {
  /// A pole enters when seen in at least this many scans of the span. Default 8.
  std::size_t min_sightings = 8;
  /// Common pole radius to state in the observations, metres; unset: to be estimated.
  std::optional<double> landmark_radius_m;
};

class SightingWindow {
 public:
  /// Holds at most `capacity` scans (>= 1).
  explicit SightingWindow(std::size_t capacity);

  /// Appends a scan; its index must exceed the last one's. The oldest leaves beyond capacity.
  void push(WatchedScan scan);
  /// Renames merged tracks (PoleTracker's TrackedScan::merged) in the scans held.
  void rename(const std::vector<std::pair<PoleId, PoleId>>& merged);

  bool empty() const { return scans_.empty(); }
  std::size_t size() const { return scans_.size(); }    ///< scans held
  std::size_t sightings() const { return sightings_; }  ///< pole sightings in them
  const WatchedScan& oldest() const { return scans_.front(); }
  const WatchedScan& newest() const { return scans_.back(); }
  /// The scan with this index; null when it is not held.
  const WatchedScan* find(std::size_t index) const;

  /// The observations of the scans held with index in [from, to]: every scan a stop with its
  /// pose, the poles seen in at least rules.min_sightings of them numbered 1, 2, ... by first
  /// sighting, their sightings by scan and pole.
  LandmarkObservations observations(std::size_t from, std::size_t to, const SpanRules& rules) const;
  /// Poles of that span that enter its observations.
  std::size_t polesIn(std::size_t from, std::size_t to, const SpanRules& rules) const;

 private:
  std::size_t capacity_;
  std::deque<WatchedScan> scans_;
  std::size_t sightings_ = 0;
};

}  // namespace lidarcal::watch
