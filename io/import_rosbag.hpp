#pragma once
// ROS1 bag importer (sensor_msgs/LaserScan), reading through Debian's ROS1 libraries
// (rosbag_storage: rosbag::Bag + rosbag::View), not a parser of our own. Built only when
// those libraries were found (CMake option LIDARCAL_WITH_ROSBAG); otherwise every function
// throws InputError saying how to enable it. The ROS headers stay in import_rosbag.cpp.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "io/import.hpp"

namespace lidarcal::io {

/// True when this build can read ROS1 bags.
bool rosbagSupported();
/// Throws InputError (naming `bag` and how to enable bag support) when this build cannot read bags.
void requireRosbagSupport(const std::filesystem::path& bag);

/// One topic of a bag.
struct BagTopic {
  std::string topic;        ///< topic name, e.g. /scan
  std::string datatype;     ///< message type, e.g. sensor_msgs/LaserScan
  std::size_t messages = 0; ///< messages on the topic
};

/// Lists the topics of a bag (sorted by name). Throws InputError when the bag cannot be read.
std::vector<BagTopic> listBagTopics(const std::filesystem::path& bag);

/// Where VIEWPOINT comes from (`import --pose odom:TOPIC|tf:FRAME`).
struct BagPoseConfig {
  enum class Kind {
    none,  ///< identity for every scan (default)
    odom,  ///< nav_msgs/Odometry on `name`, composed with the sensor's mount from /tf_static when there
    tf,    ///< the chain from the fixed frame `name` to the scan's frame_id through /tf and /tf_static
  };
  Kind kind = Kind::none;
  std::string name;            ///< odom: the topic; tf: the fixed frame
  double hold_s = 0.1;         ///< a scan this close (s) before the first or after the last pose sample takes that sample; default 0.1
  double still_m = 0.01;       ///< poses within this distance (m) ...
  double still_rad = 0.00872664626;  ///< ... and this heading (rad, default 0.5 deg) of the stop's first pose are that pose
};

struct RosbagConfig {
  /// sensor_msgs/LaserScan topic to read; default empty = the bag's only LaserScan topic
  /// (an error naming the candidates when there are several).
  std::string topic;
  std::optional<double> range_min_m;  ///< overrides each message's range_min, metres; default: the message's
  std::optional<double> range_max_m;  ///< overrides each message's range_max, metres; default: the message's
  BagPoseConfig pose;                 ///< VIEWPOINT source; default identity

  /// Throws InputError when the limits are inconsistent.
  void validate() const;
};

/// Streams the LaserScan messages of one topic to `on_scan`, in bag (time) order. Beam i is at
/// angle_min + i * angle_increment; intensities are kept when the message has one per range;
/// the pose is the identity for every scan unless config.pose names odometry or tf: then it is
/// interpolated at each scan's header stamp, held while the sensor stands still (stops), and
/// scans without a pose (before the first or after the last sample) are skipped with a note.
/// Throws InputError for an unreadable or truncated bag, a missing topic, or a topic of another
/// message type; DataError when no scan has a pose.
ImportReport readRosbag(const std::filesystem::path& bag, const RosbagConfig& config, const ScanCallback& on_scan);

}  // namespace lidarcal::io
