// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The ROS 2 messages lidarcal reads from a bag, decoded from CDR (io/cdr.hpp) by their field
// layout in the .msg definitions (sensor_msgs/msg/LaserScan, nav_msgs/msg/Odometry,
// tf2_msgs/msg/TFMessage; std_msgs/msg/Header = builtin_interfaces/msg/Time stamp {int32 sec,
// uint32 nanosec} + string frame_id). Fields after the last one needed are not read. Every
// decoder throws InputError (item "byte N of M") on a message too short for its type.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "io/bag_scans.hpp"
#include "io/pose_track.hpp"

namespace lidarcal::io {

/// sensor_msgs/msg/LaserScan; reused from message to message (its vectors keep their capacity).
struct Ros2LaserScan {
  std::int32_t stamp_sec = 0;                               ///< header.stamp.sec
  std::uint32_t stamp_nanosec = 0;                          ///< header.stamp.nanosec
  std::string frame_id;                                     ///< header.frame_id
  float angle_min = 0, angle_max = 0, angle_increment = 0;  ///< rad
  float time_increment = 0, scan_time = 0;                  ///< s
  float range_min = 0, range_max = 0;                       ///< m
  std::vector<float> ranges;                                ///< m
  std::vector<float> intensities;                           ///< sensor units
  std::size_t ranges_offset = 0;  ///< byte offset of ranges[0] in the serialised message
  bool big_endian = false;        ///< the message's CDR byte order

  /// The fields as the shared conversion (fillRawScan) takes them; views into this message.
  LaserScanView view() const;
};
void decodeLaserScan(const std::uint8_t* data, std::size_t size, Ros2LaserScan& msg);
/// Writes msg.ranges back into the serialised message `msg` was decoded from (same size, same
/// byte order, at msg.ranges_offset): every other byte stays as it was.
void patchLaserScanRanges(const Ros2LaserScan& msg, std::uint8_t* data, std::size_t size);

/// A stamped transform of a tf message or the pose of an odometry message.
struct Ros2StampedTransform {
  double stamp_s = 0.0;  ///< header.stamp, seconds
  std::string parent;    ///< header.frame_id
  std::string child;     ///< child_frame_id
  Transform3 transform;  ///< child -> parent
};
/// nav_msgs/msg/Odometry: header, child_frame_id and pose.pose (the covariance and twist are not
/// read).
Ros2StampedTransform decodeOdometry(const std::uint8_t* data, std::size_t size);
/// sensor_msgs/msg/JointState: the stamp, the joints' names and positions (velocity and effort
/// are not read).
struct Ros2JointState {
  double stamp_s = 0.0;
  std::vector<std::string> name;
  std::vector<double> position;
};
/// Decodes into `out` (its vectors are reused).
void decodeJointState(const std::uint8_t* data, std::size_t size, Ros2JointState& out);
/// tf2_msgs/msg/TFMessage: sequence<geometry_msgs/msg/TransformStamped>.
std::vector<Ros2StampedTransform> decodeTfMessage(const std::uint8_t* data, std::size_t size);

}  // namespace lidarcal::io
