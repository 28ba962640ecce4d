// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ROS1 bag importer (sensor_msgs/LaserScan), reading through Debian's ROS1 libraries
// (rosbag_storage: rosbag::Bag + rosbag::View), not a parser of our own. Built only when
// those libraries were found (CMake option LIDARCAL_WITH_ROSBAG); otherwise every function
// throws InputError saying how to enable it. The ROS headers stay in import_rosbag.cpp.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "io/bag_scans.hpp"
#include "io/import.hpp"

namespace lidarcal::io {

/// True when this build can read ROS1 bags.
bool rosbagSupported();
/// Throws InputError (naming `bag` and how to enable bag support) when this build cannot read bags.
void requireRosbagSupport(const std::filesystem::path& bag);

/// Lists the topics of a bag (sorted by name). Throws InputError when the bag cannot be read.
std::vector<BagTopic> listBagTopics(const std::filesystem::path& bag);

/// Streams the LaserScan messages of one topic to `on_scan`, in bag (time) order. Beam i is at
/// angle_min + i * angle_increment; intensities are kept when the message has one per range;
/// the pose is the identity for every scan unless config.pose names odometry or tf: then it is
/// interpolated at each scan's header stamp, held while the sensor stands still (stops), and
/// scans without a pose (before the first or after the last sample) are skipped with a note.
/// Throws InputError for an unreadable or truncated bag, a missing topic, or a topic of another
/// message type; DataError when no scan has a pose.
ImportReport readRosbag(const std::filesystem::path& bag, const RosbagConfig& config,
                        const ScanCallback& on_scan);

}  // namespace lidarcal::io
