// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CSV importer for recordings in any other format: one row per beam, a header naming the
// columns (any order; unknown columns are ignored), rows of one scan consecutive:
//
//   scan,x_m,y_m,yaw_rad,angle_rad,range_m[,intensity][,stamp_s]
//
// `scan` is an integer that increases from one scan to the next; the pose columns (the sensor
// pose in the world frame) are the same on every row of a scan; `angle_rad` is the beam's bearing
// in the sensor frame (counter-clockwise from forward); `range_m` is empty, `nan` or <= 0 for a
// beam without return. Lines starting with '#' are comments. Full description: docs/FORMAT.md.

#include <filesystem>
#include <limits>

#include "io/import.hpp"

namespace lidarcal::io {

struct CsvConfig {
  double range_min_m = 0.0;  ///< readings below are beams without return, metres; default 0
  /// readings above are beams without return; default unbounded
  double range_max_m = std::numeric_limits<double>::infinity();

  /// Throws InputError when the limits are inconsistent.
  void validate() const;
};

/// Streams the scans of a CSV file (plain or gzip) to `on_scan`. Throws InputError naming the
/// line for a missing column, a malformed value, a pose that changes within a scan or rows of a
/// scan that are not consecutive.
ImportReport readCsvScans(const std::filesystem::path& csv, const CsvConfig& config,
                          const ScanCallback& on_scan);

}  // namespace lidarcal::io
