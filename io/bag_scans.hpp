// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the ROS1 bag reader (import_rosbag.cpp, built with Debian's ROS1 libraries) and the
// ROS 2 bag reader (import_rosbag2.cpp, built always) share: the options, the choice of the
// LaserScan topic, the conversion of one LaserScan into a RawScan, and the poses (odometry, tf)
// with the stop filter and the report notes. No ROS types: each reader fills LaserScanView and
// BagPoses from its own messages.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "io/import.hpp"
#include "io/pose_track.hpp"
#include "io/wheel_track.hpp"

namespace lidarcal::io {

/// One topic of a bag.
struct BagTopic {
  std::string topic;  ///< topic name, e.g. /scan
  /// message type, e.g. sensor_msgs/LaserScan (ROS1) or sensor_msgs/msg/LaserScan (ROS 2)
  std::string datatype;
  std::size_t messages = 0;  ///< messages on the topic
};

/// Where VIEWPOINT comes from (`import --pose odom:TOPIC|tf:FRAME`).
struct BagPoseConfig {
  enum class Kind {
    none,  ///< identity for every scan (default)
    /// nav_msgs/Odometry on `name`, composed with the sensor's mount from /tf_static when there
    odom,
    /// the chain from the fixed frame `name` to the scan's frame_id through /tf and /tf_static
    tf,
  };
  Kind kind = Kind::none;
  std::string name;  ///< odom: the topic; tf: the fixed frame
  /// a scan this close (s) before the first or after the last pose sample takes that sample;
  /// default 0.1
  double hold_s = 0.1;
  double still_m = 0.01;  ///< poses within this distance (m) ...
  /// ... and this heading (rad, default 0.5 deg) of the stop's first pose are that pose
  double still_rad = 0.00872664626;
  /// Rig import: also the pose of this frame (the vehicle's) and the scan frame's mounting on it
  /// (RawScan::vehicle_pose, RawScan::mounting; /tf_static is read even without a pose source).
  /// "auto": the frame just below the first moving (/tf) link above the scan frame, or the top of
  /// its static chain. Default empty: none.
  std::string vehicle_frame;
};

struct RosbagConfig {
  /// sensor_msgs/LaserScan topic to read; default empty = the bag's only LaserScan topic
  /// (an error naming the candidates when there are several).
  std::string topic;
  /// overrides each message's range_min, metres; default: the message's
  std::optional<double> range_min_m;
  /// overrides each message's range_max, metres; default: the message's
  std::optional<double> range_max_m;
  BagPoseConfig pose;  ///< VIEWPOINT source; default identity
  WheelJoints wheels;  ///< the wheels' joint states to look up at each scan; default none

  /// Throws InputError when the limits are inconsistent.
  void validate() const;
};

/// The names one bag flavour uses (ROS1 or ROS 2), for choosing topics and for messages.
struct BagFlavour {
  const char* from;        ///< the --from value: rosbag1 or rosbag2
  const char* label;       ///< for sensor_name: ROS1 or ROS 2
  const char* scan_type;   ///< sensor_msgs/LaserScan or sensor_msgs/msg/LaserScan
  const char* odom_type;   ///< nav_msgs/Odometry or nav_msgs/msg/Odometry
  const char* joint_type;  ///< sensor_msgs/JointState or sensor_msgs/msg/JointState
};
inline constexpr BagFlavour kRos1Flavour{"rosbag1", "ROS1", "sensor_msgs/LaserScan",
                                         "nav_msgs/Odometry", "sensor_msgs/JointState"};
inline constexpr BagFlavour kRos2Flavour{"rosbag2", "ROS 2", "sensor_msgs/msg/LaserScan",
                                         "nav_msgs/msg/Odometry", "sensor_msgs/msg/JointState"};

/// Checks that the bag has `joints.topic` with `flavour`'s JointState type; throws InputError
/// naming the option otherwise.
void checkWheelTopic(const std::filesystem::path& file, const std::vector<BagTopic>& topics,
                     const WheelJoints& joints, const BagFlavour& flavour);

/// The LaserScan topic to read: `wanted`, checked, or the bag's only LaserScan topic. Throws
/// InputError naming the LaserScan topics when there is none, several or `wanted` is not one.
std::string chooseScanTopic(const std::filesystem::path& file, const std::vector<BagTopic>& topics,
                            const std::string& wanted, const BagFlavour& flavour);

/// The topics --pose needs read (odometry topic, /tf_static, /tf), checked against the bag's
/// topics: throws InputError when the odometry topic is missing or of another type, or when
/// tf:FRAME is asked of a bag without /tf and /tf_static.
std::vector<std::string> poseTopics(const std::filesystem::path& file,
                                    const std::vector<BagTopic>& topics,
                                    const BagPoseConfig& config, const BagFlavour& flavour);

/// A LaserScan's fields (ROS1 and ROS 2 have the same), the arrays as views into the message.
struct LaserScanView {
  std::int64_t stamp_sec = 0;       ///< header.stamp seconds
  std::uint32_t stamp_nanosec = 0;  ///< header.stamp nanoseconds
  float angle_min = 0.0f;           ///< rad
  float angle_increment = 0.0f;     ///< rad
  float range_min = 0.0f;           ///< m
  float range_max = 0.0f;           ///< m
  const float* ranges = nullptr;    ///< m, `count` values
  std::size_t count = 0;
  const float* intensities = nullptr;  ///< `intensity_count` values
  std::size_t intensity_count = 0;
};

/// A ROS1 sensor_msgs/LaserScan's fields as a LaserScanView (the bag reader's and lidarcal_node's;
/// a template so that this header needs no ROS types).
template <class Ros1LaserScan>
LaserScanView ros1ScanView(const Ros1LaserScan& msg) {
  LaserScanView v;
  v.stamp_sec = msg.header.stamp.sec;
  v.stamp_nanosec = msg.header.stamp.nsec;
  v.angle_min = msg.angle_min;
  v.angle_increment = msg.angle_increment;
  v.range_min = msg.range_min;
  v.range_max = msg.range_max;
  v.ranges = msg.ranges.data();
  v.count = msg.ranges.size();
  v.intensities = msg.intensities.data();
  v.intensity_count = msg.intensities.size();
  return v;
}

/// The importer's view of a LaserScan (pose left as it is): beam i at angle_min + i *
/// angle_increment, intensities kept when there is one per range, range limits from the
/// message (as the decimal they were written as) unless `config` overrides them.
void fillRawScan(const LaserScanView& msg, const RosbagConfig& config, RawScan& scan);

/// The poses a bag records for --pose: an odometry track or a tf tree, filled by the reader (or,
/// live, by lidarcal_ros2_node's pose input with the same rules).
class BagPoses {
 public:
  explicit BagPoses(const BagPoseConfig& config) : config_(config) {}
  void addOdometry(double stamp_s, const Transform3& pose, const std::string& child_frame);
  void addTransform(const std::string& parent, const std::string& child, double stamp_s,
                    const Transform3& t, bool is_static);
  /// Throws DataError when --pose odom: found no odometry message on its topic.
  void checkFilled(const std::filesystem::path& file) const;
  /// The sensor's pose at the scan's stamp, or nothing (and why). odom: `mount_missing` (when
  /// given) tells whether the pose is the odometry's child frame's because /tf_static has no
  /// link from it to `frame`.
  std::optional<Transform3> at(const std::string& frame, double stamp_s, std::string& why,
                               bool* mount_missing = nullptr);
  /// Notes for the report.
  std::vector<std::string> notes() const;
  /// Rig import: the vehicle's pose and the scan frame's mounting at `stamp_s` into `scan`.
  void addRigPoses(const std::string& frame, double stamp_s, RawScan& scan) const;
  /// True once an odometry message was added.
  bool hasOdometry() const { return !odom_.empty(); }
  /// A live stream's poses: TransformTrack::keepWithin on the odometry and every /tf edge.
  void keepWithin(double window_s, std::size_t max_samples) {
    odom_.keepWithin(window_s, max_samples);
    tree_.keepWithin(window_s, max_samples);
  }

 private:
  BagPoseConfig config_;
  TransformTrack odom_;
  std::string odom_child_;
  TransformTree tree_;
  bool mount_missing_ = false;
};

/// What to do when most stops hold one or two scans (ImportReport::short_stops): the tolerances
/// to try.
std::string shortStopsAdvice();

/// What both readers do with each converted scan: its pose (when --pose), the stop filter, the
/// count and the callback; then the checks and notes of the report.
class BagScanSink {
 public:
  BagScanSink(const BagPoseConfig& config, BagPoses& poses, const ScanCallback& on_scan,
              ImportReport& report);
  /// Hands `scan` on with its pose (skipped without one). Returns false when the callback asks to
  /// stop.
  bool offer(RawScan& scan, const std::string& frame_id);
  /// Throws DataError when no scan had a pose, InputError when the topic had no message; adds the
  /// notes.
  void finish(const std::filesystem::path& file, const std::string& topic);

 private:
  const BagPoseConfig& config_;
  BagPoses& poses_;
  const ScanCallback& on_scan_;
  ImportReport& report_;
  StillPoseFilter still_;
  std::size_t without_pose_ = 0;
  std::string first_why_;
  bool upside_down_ = false;
};

/// A transform from a ROS position and quaternion (Eigen's (w, x, y, z)); an unset (all-zero)
/// quaternion is the identity, as tf takes it; others are normalised.
Transform3 makeTransform(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation);

/// A frame name without its leading slash (ROS1 tf allowed one).
std::string stripSlash(const std::string& frame);

}  // namespace lidarcal::io
