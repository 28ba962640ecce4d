// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The vehicle's poses for a live node, without DDS: transforms as they arrive from
// nav_msgs/msg/Odometry, /tf and /tf_static, checked, kept for a short time and looked up at a
// scan's stamp by the rules of `lidarcal import --pose` (io::BagPoses: odometry composed with the
// sensor's mount from /tf_static, or the chain from a fixed frame through /tf and /tf_static;
// linear interpolation in position, slerp in rotation). A message that cannot be a pose is
// dropped and counted with its reason; it never throws.

#include <array>
#include <cstddef>
#include <optional>
#include <string>

#include "common/pose2.hpp"
#include "io/bag_scans.hpp"
#include "ros2/node_args.hpp"
#include "ros2/node_messages.hpp"

namespace lidarcal::ros2 {

/// One transform as received: the pose of `child` in `parent` (an Odometry's pose, or one
/// geometry_msgs/msg/TransformStamped of a TFMessage).
struct ReceivedTransform {
  RosTime stamp;               ///< header.stamp
  std::string parent;          ///< header.frame_id (a leading '/' is ignored)
  std::string child;           ///< child_frame_id (a leading '/' is ignored)
  double x = 0, y = 0, z = 0;  ///< translation, m
  /// rotation as a quaternion; all zero is the identity (as tf takes it), others are normalised
  double qx = 0, qy = 0, qz = 0, qw = 1;
};

/// Why a received transform was dropped.
enum class PoseDropReason {
  /// nanosec not below 1e9, or (odometry, /tf) a stamp at or before the epoch (unset)
  bad_stamp,
  empty_frame,     ///< header.frame_id or child_frame_id empty
  self_transform,  ///< parent and child are the same frame
  non_finite,      ///< a translation or quaternion component is NaN or infinite
  count_
};
const char* toString(PoseDropReason r);

struct LivePoseSettings {
  /// odom: `name` is the resolved odometry topic (for messages); tf: the fixed frame. Default
  /// odom:odom.
  PoseSource source;
  /// a stamp this close (s) before the first or after the last sample takes that sample; default
  /// 0.1, as import
  double hold_s = 0.1;
  double window_s = 10.0;  ///< samples kept per moving frame: this many seconds back, default 10
  std::size_t max_samples = 2000;  ///< and at most this many per moving frame, default 2000
};

/// A pose looked up, or why there is none.
struct PoseLookup {
  std::optional<Pose2> pose;  ///< the frame's x, y (m) and yaw (rad) in the fixed frame
  std::string fixed_frame;    ///< the frame `pose` is in (odom: the odometry's header.frame_id)
  std::string why;            ///< without a pose: the missing link or the stamps held
  /// odom: /tf_static has no link from the odometry's child frame to the scan's frame, so `pose`
  /// is the child frame's (the sensor taken as mounted at its origin); default false
  bool mount_missing = false;
};

/// Counts over the node's life.
struct LivePoseStats {
  std::size_t odometry = 0;    ///< odometry messages kept
  std::size_t transforms = 0;  ///< tf transforms kept (/tf and /tf_static)
  std::array<std::size_t, static_cast<std::size_t>(PoseDropReason::count_)>
      dropped{};  ///< by reason
  std::size_t droppedTotal() const;
};

class LivePoses {
 public:
  explicit LivePoses(const LivePoseSettings& settings);

  /// An odometry message: the pose of child_frame_id in header.frame_id. Returns the reason when
  /// it is dropped. Ignored (not dropped) with a tf source.
  std::optional<PoseDropReason> addOdometry(const ReceivedTransform& t);
  /// One transform of /tf (is_static false) or /tf_static (true). Returns the reason when it is
  /// dropped.
  std::optional<PoseDropReason> addTransform(const ReceivedTransform& t, bool is_static);

  /// The pose of `frame` (a scan's header.frame_id) at `stamp` in the fixed frame.
  PoseLookup at(const std::string& frame, const RosTime& stamp);

  const LivePoseStats& stats() const { return stats_; }

 private:
  std::optional<PoseDropReason> check(const ReceivedTransform& t, bool is_static);

  LivePoseSettings settings_;
  io::BagPoses poses_;
  std::string odom_frame_;  // header.frame_id of the odometry (its fixed frame)
  LivePoseStats stats_;
};

}  // namespace lidarcal::ros2
