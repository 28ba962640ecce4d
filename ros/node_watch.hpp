// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// lidarcal_node's outputs and inputs beside the scans (ROS 1): the poses the watcher needs
// (nav_msgs/Odometry, or /tf, and /tf_static for the sensor's mount), the watcher's events in the
// log (alarms with their evidence, switches with both models) and learn mode's candidates on a
// latched topic and in a file, and the /diagnostics status every period (every mode). All run
// in the node's spin thread; nothing here throws on a bad message.

#include <cstddef>
#include <string>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>

#include "ros/node_params.hpp"
#include "ros/scan_path.hpp"

namespace lidarcal::ros1 {

/// Feeds received poses to a ScanPath (ros2::LivePoses: the rules of `import --pose`). A message
/// that cannot be a pose is dropped and counted, with a warning now and then.
class PoseInput {
 public:
  PoseInput(ros::NodeHandle& nh, const ros2::PoseSource& source, ros2::LivePoses& poses);

 private:
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  void onTransforms(const tf2_msgs::TFMessage::ConstPtr& msg, bool is_static);

  ros2::LivePoses& poses_;
  std::vector<ros::Subscriber> subscribers_;
};

/// The watcher's events as the node reports them: alarms (ROS_WARN with the evidence), switches
/// (both models' bias at 1, 2, 3 m and the decision's reason), learn mode's candidates (each
/// refit with status ok as model.json text on the latched candidate topic and, when set, in the
/// candidate file, written atomically, adopted or not), scans left out of watching (a warning now
/// and then).
class WatchReporter {
 public:
  WatchReporter(ros::NodeHandle& nh, const WatchParameters& p);
  void report(const ScanOutcome& out, const ScanPathStats& stats);

 private:
  void reportRefit(const watch::RefitEvent& e);
  std::string publishCandidate(const CalibrationModel& candidate);

  WatchParameters params_;
  ros::Publisher candidates_;  // learn mode only
  std::string candidate_topic_;
};

/// Publishes ScanPath::report() on /diagnostics (diagnostic_msgs/DiagnosticArray, one status)
/// every period.
class DiagnosticsOutput {
 public:
  /// `name`: the status's name; `hardware_id`: the sensor's name ("" until setHardwareId).
  DiagnosticsOutput(ros::NodeHandle& nh, double period_s, std::string name, std::string hardware_id,
                    const ScanPath& path);
  const std::string& hardwareId() const { return hardware_id_; }
  void setHardwareId(std::string id) { hardware_id_ = std::move(id); }

 private:
  void publish(const ros::TimerEvent&);

  std::string name_, hardware_id_;
  const ScanPath& path_;
  ros::Publisher publisher_;
  ros::Timer timer_;
};

}  // namespace lidarcal::ros1
