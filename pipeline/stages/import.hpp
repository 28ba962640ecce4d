// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// `lidarcal import`: a recording (ROS1 bag, ROS 2 bag, CARMEN log, YDLIDAR X4 .dat, CSV) streamed
// scan by scan into a PCD scan sequence. Composition of an io importer and io::SequenceWriter.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "io/import.hpp"
#include "io/import_carmen.hpp"
#include "io/import_rosbag.hpp"
#include "io/sequence_writer.hpp"

namespace lidarcal::pipeline {

enum class ImportFormat { rosbag1, rosbag2, carmen, ydlidar, csv };

/// Parses "rosbag1", "rosbag2", "carmen", "ydlidar" or "csv"; throws InputError otherwise.
ImportFormat parseImportFormat(const std::string& name);
const char* toString(ImportFormat format);

struct ImportSettings {
  ImportFormat format = ImportFormat::csv;  ///< what the input is
  /// the recordings (read only), imported one after the other
  std::vector<std::filesystem::path> inputs;
  /// Each input begins a new stop, even where the poses of consecutive inputs are equal
  /// (recordings taken apart at one pose; sequence.json `stop_starts`). Default false.
  bool stop_per_input = false;
  std::filesystem::path out;        ///< the sequence directory to create
  io::SequenceWriterConfig writer;  ///< --every, --max-scans, --overwrite, encoding
  std::string topic;                ///< rosbag1/rosbag2: LaserScan topic; empty = the only one
  io::CarmenPose carmen_pose = io::CarmenPose::corrected;  ///< carmen: pose written to VIEWPOINT
  io::BagPoseConfig bag_pose;  ///< rosbag1/rosbag2: VIEWPOINT source (default: identity)
  io::WheelJoints wheels;      ///< rosbag1/rosbag2: the wheels' joint states (wheel_angles.csv)
  std::optional<double> range_min_m;  ///< overrides the format's lower range limit, metres
  std::optional<double> range_max_m;  ///< overrides the format's upper range limit, metres
  std::string sensor_name;  ///< sensor_name for sequence.json; empty = what the input says
};

struct ImportResult {
  io::ImportReport read;             ///< what the importer read
  io::SequenceWriteSummary written;  ///< what was written
};

/// Imports settings.inputs into settings.out, in the order given. `on_progress` (optional)
/// receives the fraction of the inputs read, 0..1 (each input an equal share). Nothing appears at
/// settings.out unless the whole import succeeds. Throws InputError for bad input or options.
ImportResult importRecording(const ImportSettings& settings,
                             const std::function<void(double)>& on_progress = {});

/// Streams the scans of one recording (settings.format, topic, pose and range limits; the
/// output settings are not used) to `on_scan`, as importRecording reads each input.
io::ImportReport readRecording(const ImportSettings& settings, const std::filesystem::path& input,
                               const io::ScanCallback& on_scan);

/// The format of one recording, from its content. Throws InputError naming the file when it
/// cannot be told (give --from).
ImportFormat detectImportFormat(const std::string& input);

/// A bag's --pose: odom:TOPIC (nav_msgs/Odometry) or tf:FIXED_FRAME. Throws InputError naming
/// --pose otherwise.
io::BagPoseConfig parseBagPose(const std::string& spec);

/// True for the bag formats (rosbag1, rosbag2): --topic, --list-topics and --pose odom:|tf: apply.
bool isBag(ImportFormat format);
/// The topics of a bag of either format (`import --list-topics`).
std::vector<io::BagTopic> listTopics(ImportFormat format, const std::filesystem::path& bag);

}  // namespace lidarcal::pipeline
