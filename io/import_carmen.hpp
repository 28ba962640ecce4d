// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CARMEN log importer (plain or gzip). Reads the front-laser lines, FLASER or ROBOTLASER1
// (whichever comes first; the other kind is ignored), one scan per line, and skips every
// other message (ODOM, PARAM, NEFF, ...). Line formats and angle conventions: docs/FORMAT.md.
//
//   FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
//   ROBOTLASER1 laser_type start_angle fov angular_resolution max_range accuracy remission_mode
//               n r1..rn m rem1..remm laser_x laser_y laser_theta robot_x robot_y robot_theta
//               tv rv forward_safety_dist side_safety_dist turn_axis timestamp hostname
//               logger_timestamp

#include <filesystem>
#include <optional>

#include "io/import.hpp"

namespace lidarcal::io {

/// Which pose of a laser line goes into VIEWPOINT.
enum class CarmenPose {
  /// FLASER `x y theta` / ROBOTLASER1 `laser_pose`: the laser's pose (SLAM-corrected in *-corrected
  /// logs)
  corrected,
  /// FLASER `odom_x odom_y odom_theta` / ROBOTLASER1 `robot_pose`: the robot's odometry pose
  odometry,
};

struct CarmenConfig {
  /// pose written to VIEWPOINT; default the (corrected) laser pose
  CarmenPose pose = CarmenPose::corrected;
  double range_min_m = 0.0;  ///< readings below are beams without return, metres; default 0
  /// Readings above are beams without return, metres. Default: 80 m for FLASER (a SICK LMS
  /// measures up to 80 m and writes 81.83 or 81.91 m for "no return"), the line's own
  /// max_range for ROBOTLASER1.
  std::optional<double> range_max_m;

  /// Throws InputError when the limits are inconsistent.
  void validate() const;
};

/// Default upper range limit for FLASER lines, metres.
constexpr double kFlaserRangeMax_m = 80.0;

/// Streams the laser lines of a CARMEN log to `on_scan`. Throws InputError naming the line when
/// a laser line is malformed (wrong number of values, not a number), when the gzip data is
/// damaged, or when the log holds no laser line.
ImportReport readCarmenLog(const std::filesystem::path& log, const CarmenConfig& config,
                           const ScanCallback& on_scan);

}  // namespace lidarcal::io
