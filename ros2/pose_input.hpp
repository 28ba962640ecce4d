// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The node's pose input on the ROS 2 graph: readers of nav_msgs/msg/Odometry (pose source
// odom:TOPIC) or /tf (tf:FRAME), and of /tf_static (both: the sensor's mount), feeding
// ros2::LivePoses, which checks each transform, keeps a short time-ordered buffer and looks up
// the scan frame's pose at a scan's stamp. QoS as the ROS 2 tools use them: the odometry best
// effort (matches every publisher) keeping the last 100; /tf reliable, keep last 100, volatile,
// and /tf_static reliable, keep last 100, transient local (tf2_ros: tf2_ros/qos.hpp, the
// listeners' profiles). A malformed message is dropped and counted, never thrown on; what the
// DDS cannot decode is discarded by Cyclone before it reaches the node.

#include <string>
#include <vector>

#include "ros2/live_poses.hpp"
#include "ros2/ros_participant.hpp"

namespace lidarcal::ros2 {

/// A received transform that was dropped, with a text for a (rate-limited) warning.
struct PoseDrop {
  PoseDropReason reason = PoseDropReason::bad_stamp;  ///< why
  std::string text;  ///< topic, stamp and frames of the message, and why
};

class PoseInput {
 public:
  /// The readers on `participant` for `settings.source` (odom: `source.name` is the resolved
  /// topic, e.g. "/odom"). Throws std::runtime_error when Cyclone refuses.
  PoseInput(RosParticipant& participant, const LivePoseSettings& settings);

  /// Takes every message received since the last call, without waiting. Returns the ones
  /// dropped.
  std::vector<PoseDrop> poll();
  /// The pose of `frame` at `stamp` (call poll() first): LivePoses::at.
  PoseLookup at(const std::string& frame, const RosTime& stamp) { return poses_.at(frame, stamp); }
  const LivePoseStats& stats() const { return poses_.stats(); }

 private:
  void offer(const ReceivedTransform& t, const char* topic, bool odometry, bool is_static,
             std::vector<PoseDrop>& drops);

  LivePoses poses_;
  std::string odom_topic_;
  int odom_reader_ = 0, tf_reader_ = 0, tf_static_reader_ = 0;  // 0: not read
};

}  // namespace lidarcal::ros2
