// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What kind of recording a file holds, from its content (not its name): `lidarcal import`
// without --from. Reads at most the first 64 KiB (after gzip decompression for gzip files); a
// directory is a ROS 2 bag when it holds metadata.yaml.

#include <filesystem>
#include <string>

namespace lidarcal::io {

enum class RecordingKind {
  unknown,  ///< none of the below
  rosbag1,  ///< ROS1 bag: starts with `#ROSBAG V2.0`
  mcap,     ///< MCAP (ROS 2 and others): starts with the magic `\x89MCAP0\r\n`; read as a ROS 2 bag
  /// ROS 2 bag: a directory with metadata.yaml, or an SQLite file (`SQLite format 3\0`, a .db3)
  rosbag2,
  /// CARMEN log (plain or gzip): its first record line starts with a CARMEN keyword (FLASER, ODOM,
  /// PARAM, ...)
  carmen,
  /// YDLIDAR X4 dataset `.dat` (plain or gzip): rows of at least 4 comma-separated numbers, no
  /// header
  ydlidar,
  csv,  ///< lidarcal's CSV (plain or gzip): a header naming range_m and angle_rad
};
const char* toString(RecordingKind kind);

struct DetectedFormat {
  RecordingKind kind = RecordingKind::unknown;
  bool gzip = false;  ///< the file is gzip-compressed (the kinds above are those of the content)
  /// what decided it, for messages (e.g. "first record line starts with FLASER")
  std::string evidence;
};

/// Looks at the start of `file` (or, for a directory, for its metadata.yaml). Throws InputError
/// when it cannot be read (missing, a directory without metadata.yaml, no permission); an
/// unrecognised content is kind unknown, not an error.
DetectedFormat detectRecordingFormat(const std::filesystem::path& file);

}  // namespace lidarcal::io
