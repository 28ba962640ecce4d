// SPDX-License-Identifier: BSD-3-Clause
#include "io/import_rosbag2.hpp"

#include <algorithm>

#include "common/errors.hpp"
#include "io/ros2_msgs.hpp"
#include "io/rosbag2_storage.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;

const Rosbag2Topic& topicOf(const Rosbag2& bag, const std::string& name) {
  const auto& topics = bag.topics();
  return *std::find_if(topics.begin(), topics.end(),
                       [&](const Rosbag2Topic& t) { return t.topic.topic == name; });
}

/// Only CDR is decoded (what every ROS 2 rmw writes).
void requireCdr(const fs::path& file, const Rosbag2& bag, const std::string& topic) {
  const std::string& encoding = topicOf(bag, topic).encoding;
  if (encoding != "cdr")
    throw InputError(file.string(), "topic " + topic,
                     "is serialised as '" + encoding + "', not cdr",
                     "lidarcal reads ROS 2 messages in CDR only");
}

/// Runs `decode`; a message that does not decode is an InputError naming the topic and message.
template <typename F>
void decodeOrExplain(const fs::path& file, const std::string& topic, std::size_t index,
                     const char* type, F&& decode) {
  try {
    decode();
  } catch (const InputError& e) {
    throw InputError(file.string(),
                     "topic " + topic + ", message " + std::to_string(index) + ", " + e.item(),
                     std::string("is not a valid CDR ") + type + ": " + e.problem(),
                     "the bag is damaged, or the topic holds another type than it declares");
  }
}

/// Fills `poses` from the odometry and tf topics --pose needs (nav_msgs/msg/Odometry,
/// tf2_msgs/msg/TFMessage).
void readPoses(const Rosbag2& bag, const fs::path& file, const BagPoseConfig& config,
               BagPoses& poses) {
  const std::vector<std::string> names = poseTopics(file, bag.bagTopics(), config, kRos2Flavour);
  for (const std::string& topic : names) requireCdr(file, bag, topic);
  std::size_t index = 0;
  bag.forEach({names.begin(), names.end()}, [&](const Rosbag2Message& m) {
    const bool odom = config.kind == BagPoseConfig::Kind::odom && *m.topic == config.name;
    if (odom) {
      decodeOrExplain(file, *m.topic, index, kRos2Flavour.odom_type, [&] {
        const Ros2StampedTransform o = decodeOdometry(m.data, m.size);
        poses.addOdometry(o.stamp_s, o.transform, o.child);
      });
    } else {
      decodeOrExplain(file, *m.topic, index, "tf2_msgs/msg/TFMessage", [&] {
        for (const auto& t : decodeTfMessage(m.data, m.size))
          poses.addTransform(t.parent, t.child, t.stamp_s, t.transform, *m.topic == "/tf_static");
      });
    }
    ++index;
    return true;
  });
  poses.checkFilled(file);
}

/// The wheels' angles from the JointState topic --wheels names (sensor_msgs/msg/JointState).
void readWheels(const Rosbag2& bag, const fs::path& file, const WheelJoints& joints,
                WheelTrack& track) {
  if (!joints.enabled()) return;
  checkWheelTopic(file, bag.bagTopics(), joints, kRos2Flavour);
  requireCdr(file, bag, joints.topic);
  std::size_t index = 0;
  Ros2JointState msg;
  bag.forEach({joints.topic}, [&](const Rosbag2Message& m) {
    decodeOrExplain(file, joints.topic, index++, kRos2Flavour.joint_type,
                    [&] { decodeJointState(m.data, m.size, msg); });
    track.addMessage(msg.stamp_s, msg.name, msg.position, joints);
    return true;
  });
  track.checkFilled(file, joints);
}

}  // namespace

std::vector<BagTopic> listRosbag2Topics(const fs::path& bag) { return Rosbag2(bag).bagTopics(); }

ImportReport readRosbag2(const fs::path& file, const RosbagConfig& config,
                         const ScanCallback& on_scan) {
  config.validate();
  const Rosbag2 bag(file);
  const std::string topic = chooseScanTopic(file, bag.bagTopics(), config.topic, kRos2Flavour);
  requireCdr(file, bag, topic);
  ImportReport report;
  for (const auto& t : bag.topics())
    if (t.topic.topic != topic) report.other_records += t.topic.messages;
  BagPoses poses(config.pose);
  readPoses(bag, file, config.pose, poses);
  WheelTrack wheels;
  readWheels(bag, file, config.wheels, wheels);
  BagScanSink sink(config.pose, poses, on_scan, report);
  const std::size_t total = topicOf(bag, topic).topic.messages;
  Ros2LaserScan msg;  // reused: its vectors keep their capacity
  RawScan scan;       // pose: the identity unless config.pose names a source
  std::size_t index = 0;
  bag.forEach({topic}, [&](const Rosbag2Message& m) {
    decodeOrExplain(file, topic, index, kRos2Flavour.scan_type,
                    [&] { decodeLaserScan(m.data, m.size, msg); });
    fillRawScan(msg.view(), config, scan);
    scan.wheel_angles_rad = wheels.at(scan.stamp_s);
    if (report.sensor_name.empty())
      report.sensor_name = std::string(kRos2Flavour.label) + " " + kRos2Flavour.scan_type + " on " +
                           topic + (msg.frame_id.empty() ? "" : " (frame " + msg.frame_id + ")");
    scan.source_index = index++;
    scan.progress =
        total ? std::min(1.0, static_cast<double>(index) / static_cast<double>(total)) : 1.0;
    return sink.offer(scan, msg.frame_id);
  });
  sink.finish(file, topic);
  return report;
}

}  // namespace lidarcal::io
