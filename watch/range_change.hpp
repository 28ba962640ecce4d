// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A change of the sensor injected into a recording's readings from a chosen scan on: the bump,
// the new unit or the new firmware the watcher is there to notice. `lidarcal watch --inject`
// replays a log with one to see what the watcher would catch; the tests and benches use it on
// simulated and real drives.

#include <cstddef>
#include <string>

#include "io/import.hpp"

namespace lidarcal::watch {

/// reading -> (1 + scale) reading + offset_m, for every return of every scan from from_scan on.
struct RangeChange {
  double offset_m = 0.0;      ///< added to each reading, metres. Default 0
  double scale = 0.0;         ///< relative scale change (0.01: readings 1 % long). Default 0
  std::size_t from_scan = 0;  ///< first scan changed (0-based). Default 0
  bool none() const { return offset_m == 0.0 && scale == 0.0; }
};

/// Applies the change to scan `index` (nothing before from_scan; returns without a reading stay
/// as they are).
void applyChange(const RangeChange& change, std::size_t index, io::RawScan& scan);

/// Parses "OFFSET_MM@SCAN", "SCALE%@SCAN" (e.g. "20@300", "0.3%@300") or both joined by '+'
/// ("20+0.3%@300"). Throws std::invalid_argument with what is wrong.
RangeChange parseRangeChange(const std::string& text);

}  // namespace lidarcal::watch
