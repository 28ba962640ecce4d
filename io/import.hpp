// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What every importer (ROS1 bag, CARMEN, YDLIDAR X4 dataset, CSV) hands on: one scan at a time
// in polar form, as the recording stores it. Importers stream: they refill one RawScan and call
// the ScanCallback once per scan, so memory does not grow with the length of the recording.
// The SequenceWriter (io/sequence_writer.hpp) turns the scans into a PCD scan sequence.

#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <optional>

#include "common/pose2.hpp"
#include "common/rig.hpp"

namespace lidarcal::io {

/// One scan of a recording, polar.
struct RawScan {
  /// sensor pose in the world frame (becomes VIEWPOINT); identity when the recording has none
  Pose2 pose;
  /// bearing of each beam in the sensor frame, radians, counter-clockwise from x (forward)
  std::vector<double> angles_rad;
  std::vector<float> ranges_m;  ///< reading of each beam, metres; NaN, inf or <= 0 means no return
  /// intensity of each beam in the sensor's units; empty = none recorded
  std::vector<float> intensities;
  double range_min_m = 0.0;  ///< readings below this become beams without return, metres
  /// readings above this become beams without return, metres
  double range_max_m = std::numeric_limits<double>::infinity();
  /// time stamp, seconds (informational; NaN when absent)
  double stamp_s = std::numeric_limits<double>::quiet_NaN();
  std::size_t source_index = 0;  ///< index of the scan in the recording (0-based, before --every)
  double progress = 0.0;  ///< fraction of the input read so far, 0..1 (for progress display only)
  /// Rig import (BagPoseConfig::vehicle_frame set): the vehicle frame's pose in the fixed frame at
  /// this scan's stamp (unset without --pose or when tf has none), the scan frame's mounting on
  /// the vehicle (tf, tf_static; unset when they do not connect), and the frames themselves.
  std::optional<Pose2> vehicle_pose;
  std::optional<Mounting> mounting;
  /// each wheel's angle (left, right, radians) at this scan's stamp (bags read with --wheels;
  /// unset otherwise, and for a scan outside the recorded joint states)
  std::optional<std::pair<double, double>> wheel_angles_rad;
  std::string frame_id;       ///< the scan's frame (bags; empty otherwise)
  std::string vehicle_frame;  ///< the vehicle frame the mounting is in (rig import)
};

/// Receives the scans one at a time; returns false to stop reading (enough scans).
using ScanCallback = std::function<bool(const RawScan&)>;

/// What an importer read.
struct ImportReport {
  std::size_t scans = 0;  ///< scans handed to the callback
  /// records ignored because they are not scans of the selected source (lines, messages)
  std::size_t other_records = 0;
  bool stopped_early = false;  ///< the callback asked to stop before the end of the input
  std::string sensor_name;     ///< what the input says about the sensor (for sequence.json)
  /// facts the user should know (e.g. which pose went into VIEWPOINT)
  std::vector<std::string> notes;
  /// most stops the still-pose filter found (a bag read with a pose source) hold one or two
  /// scans: the poses jitter by more than the stop tolerances, which split a sensor that stood
  /// still (BagPoseConfig::still_m, still_rad). Default false
  bool short_stops = false;
};

/// Checks a range window for the importers' configs: 0 <= range_min_m < range_max_m (max may
/// be infinite). Throws InputError naming --range-min / --range-max.
void checkRangeLimits(double range_min_m, double range_max_m);

/// A float32 value as the decimal it was written as (0.15f -> 0.15, not 0.15000000596...):
/// seven significant digits are what a float holds. ROS range limits go through it.
double float32Decimal(float value);

}  // namespace lidarcal::io
