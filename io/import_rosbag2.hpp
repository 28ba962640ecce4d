// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ROS 2 bag importer (sensor_msgs/msg/LaserScan in CDR): a .mcap file, a .db3 file or a rosbag2
// directory (io/rosbag2_storage.hpp), decoded by io/ros2_msgs.hpp. Built always (no ROS
// libraries): lidarcal's own MCAP reader, Debian's libsqlite3, libzstd and liblz4. Scans become
// RawScans exactly as in the ROS1 importer (io/bag_scans.hpp: fillRawScan, BagScanSink).

#include <filesystem>
#include <vector>

#include "io/bag_scans.hpp"
#include "io/import.hpp"

namespace lidarcal::io {

/// The topics of a ROS 2 bag, sorted by name, with their types and message counts. Throws
/// InputError when the bag cannot be read.
std::vector<BagTopic> listRosbag2Topics(const std::filesystem::path& bag);

/// Streams the LaserScan messages of one topic to `on_scan` in time order (as readRosbag for
/// ROS1: same conversion, same --pose odom:/tf: handling with nav_msgs/msg/Odometry and
/// tf2_msgs/msg/TFMessage). Throws InputError for an unreadable bag, a missing topic, a topic of
/// another type or encoding, or a message that does not decode; DataError when no scan has a pose.
ImportReport readRosbag2(const std::filesystem::path& bag, const RosbagConfig& config,
                         const ScanCallback& on_scan);

}  // namespace lidarcal::io
