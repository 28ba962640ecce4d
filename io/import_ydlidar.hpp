// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Importer for the YDLIDAR X4 dataset (BradleyWood/Lidar-Dataset, `*.dat`, plain or gzip):
// one scan per line, comma-separated,
//
//   distance, dtheta, dt, r0, r1, ..., r(n-1)
//
// distance and dtheta are the robot's odometry change since the previous line, dt the time
// since the previous line (s), r_i the range of beam i in metres at equal angular steps over
// 360 degrees (0.0 = no return). The conventions below were established from the data and the
// recording robot's code; the evidence is in docs/FORMAT.md.

#include <filesystem>

#include "common/pose2.hpp"
#include "io/import.hpp"

namespace lidarcal::io {

struct YdlidarConfig {
  /// Metres per unit of the distance column. Default 0.001: the robot's odometry wrote millimetres
  /// (BreezySLAM's PoseChange convention dxy_mm, dtheta_degrees, dt_seconds).
  double distance_unit_m = 0.001;
  /// Radians per unit of the dtheta column. Default pi/180: degrees, counter-clockwise positive.
  double dtheta_unit_rad = kPi / 180.0;
  /// Bearing of beam 0 in the robot frame, radians. Default 0: beam 0 points forward; beam i is at
  /// first_beam_rad + 2 pi i / n, counter-clockwise.
  double first_beam_rad = 0.0;
  /// readings below are beams without return, metres; default 0.12 (dataset README)
  double range_min_m = 0.12;
  /// readings above are beams without return, metres; default 10 (dataset README)
  double range_max_m = 10.0;

  /// Throws InputError when a value is out of range.
  void validate() const;
};

/// Pose after one line's odometry change: heading at the middle of the step (the step is an arc
/// approximated by a chord at the mean heading), then the heading change.
Pose2 integrateOdometry(const Pose2& previous, double distance_m, double dtheta_rad);

/// Streams the scans of a .dat file to `on_scan`. Scan 0 is at the origin: the deltas on the
/// first line describe motion before the recording started and are not applied. Throws
/// InputError naming the line for a malformed line.
ImportReport readYdlidarDat(const std::filesystem::path& dat, const YdlidarConfig& config,
                            const ScanCallback& on_scan);

}  // namespace lidarcal::io
