// SPDX-License-Identifier: BSD-3-Clause
// The only translation unit that includes ROS headers (they are slow to compile and not
// warning-clean; CMake adds them as SYSTEM includes to this library only).

#include "io/import_rosbag.hpp"
#include "io/rosbag_rewrite.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include "common/errors.hpp"
#include "io/pose_track.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;
constexpr const char* kLaserScanType = kRos1Flavour.scan_type;

void openBag(rosbag::Bag& bag, const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec))
    throw InputError(file.string(), "", "file does not exist", "check the path");
  if (fs::is_directory(file, ec))
    throw InputError(file.string(), "", "is a directory, expected a .bag file",
                     "pass the bag file");
  try {
    bag.open(file.string(), rosbag::bagmode::Read);
  } catch (const ros::Exception& e) {
    throw InputError(
        file.string(), "", std::string("cannot be read as a ROS1 bag (rosbag: ") + e.what() + ")",
        "a truncated or unindexed bag (recording interrupted) can be repaired on a copy with "
        "`rosbag reindex`; a ROS 2 bag (directory, .mcap or .db3) is read with --from rosbag2");
  }
}

std::vector<BagTopic> topicsOf(const rosbag::Bag& bag) {
  std::map<std::string, BagTopic> topics;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections()) {
    BagTopic& t = topics[c->topic];
    t.topic = c->topic;
    t.datatype = c->datatype;
  }
  for (auto& [name, t] : topics) t.messages = rosbag::View(bag, rosbag::TopicQuery(name)).size();
  std::vector<BagTopic> out;
  out.reserve(topics.size());
  for (auto& [name, t] : topics) out.push_back(std::move(t));
  return out;
}

Transform3 toTransform(const geometry_msgs::Point& p, const geometry_msgs::Quaternion& q) {
  return makeTransform({p.x, p.y, p.z}, Eigen::Quaterniond(q.w, q.x, q.y, q.z));
}

Transform3 toTransform(const geometry_msgs::Transform& tf) {
  const auto& p = tf.translation;
  const auto& q = tf.rotation;
  return makeTransform({p.x, p.y, p.z}, Eigen::Quaterniond(q.w, q.x, q.y, q.z));
}

/// Fills `poses` from the bag's odometry and tf topics that config.pose needs.
void readPoses(const rosbag::Bag& bag, const fs::path& file, const std::vector<BagTopic>& topics,
               const BagPoseConfig& config, BagPoses& poses) {
  for (const std::string& topic : poseTopics(file, topics, config, kRos1Flavour)) {
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(topic))) {
      if (topic == config.name && config.kind == BagPoseConfig::Kind::odom) {
        const nav_msgs::Odometry::ConstPtr o = m.instantiate<nav_msgs::Odometry>();
        if (o)
          poses.addOdometry(o->header.stamp.toSec(),
                            toTransform(o->pose.pose.position, o->pose.pose.orientation),
                            o->child_frame_id);
        continue;
      }
      // tf/tfMessage has the same layout
      const tf2_msgs::TFMessage::ConstPtr msg = m.instantiate<tf2_msgs::TFMessage>();
      if (!msg) continue;
      for (const auto& t : msg->transforms)
        poses.addTransform(t.header.frame_id, t.child_frame_id, t.header.stamp.toSec(),
                           toTransform(t.transform), topic == "/tf_static");
    }
  }
  poses.checkFilled(file);
}

/// The wheels' angles from the JointState topic --wheels names.
void readWheels(const rosbag::Bag& bag, const fs::path& file, const std::vector<BagTopic>& topics,
                const WheelJoints& joints, WheelTrack& track) {
  if (!joints.enabled()) return;
  checkWheelTopic(file, topics, joints, kRos1Flavour);
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(joints.topic))) {
    const sensor_msgs::JointState::ConstPtr j = m.instantiate<sensor_msgs::JointState>();
    if (j) track.addMessage(j->header.stamp.toSec(), j->name, j->position, joints);
  }
  track.checkFilled(file, joints);
}

}  // namespace

bool rosbagSupported() { return true; }
void requireRosbagSupport(const fs::path&) {}

std::vector<BagTopic> listBagTopics(const fs::path& file) {
  rosbag::Bag bag;
  openBag(bag, file);
  try {
    return topicsOf(bag);
  } catch (const ros::Exception& e) {
    throw InputError(file.string(), "",
                     std::string("the bag index cannot be read (rosbag: ") + e.what() + ")",
                     "repair a copy with `rosbag reindex`");
  }
}

ImportReport readRosbag(const fs::path& file, const RosbagConfig& config,
                        const ScanCallback& on_scan) {
  config.validate();
  rosbag::Bag bag;
  openBag(bag, file);
  ImportReport report;
  std::size_t index = 0;
  std::string topic;
  BagPoses poses(config.pose);
  BagScanSink sink(config.pose, poses, on_scan, report);
  try {
    const std::vector<BagTopic> topics = topicsOf(bag);
    topic = chooseScanTopic(file, topics, config.topic, kRos1Flavour);
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    const std::size_t total = view.size();
    for (const BagTopic& t : topics)
      if (t.topic != topic) report.other_records += t.messages;
    readPoses(bag, file, topics, config.pose, poses);
    WheelTrack wheels;
    readWheels(bag, file, topics, config.wheels, wheels);
    RawScan scan;  // pose: the identity unless config.pose names a source
    for (const rosbag::MessageInstance& m : view) {
      const sensor_msgs::LaserScan::ConstPtr msg = m.instantiate<sensor_msgs::LaserScan>();
      if (!msg)
        throw InputError(
            file.string(), "topic " + topic + ", message " + std::to_string(index),
            "is not a " + std::string(kLaserScanType) + " (type " + m.getDataType() + ")",
            "choose another topic");
      fillRawScan(ros1ScanView(*msg), config, scan);
      scan.wheel_angles_rad = wheels.at(scan.stamp_s);
      if (report.sensor_name.empty())
        report.sensor_name =
            "ROS1 " + std::string(kLaserScanType) + " on " + topic +
            (msg->header.frame_id.empty() ? "" : " (frame " + msg->header.frame_id + ")");
      scan.source_index = index++;
      scan.progress = total ? static_cast<double>(index) / static_cast<double>(total) : 1.0;
      if (!sink.offer(scan, msg->header.frame_id)) break;
    }
  } catch (const ros::Exception& e) {
    throw InputError(
        file.string(),
        topic.empty() ? std::string() : "topic " + topic + ", message " + std::to_string(index),
        std::string("cannot be read (rosbag: ") + e.what() + ")",
        "the bag is damaged; repair a copy with `rosbag reindex` or record it again");
  }
  sink.finish(file, topic);
  return report;
}

BagRewriteReport rewriteRosbag(const fs::path& in, const fs::path& out, const std::string& wanted,
                               const RangesCallback& on_scan) {
  return rewriteRosbagTopics(
      in, out, {wanted}, [&](const std::string&, std::vector<float>& ranges, const RawScan& scan) {
        on_scan(ranges, scan);
      });
}

BagRewriteReport rewriteRosbagTopics(const fs::path& in, const fs::path& out,
                                     const std::vector<std::string>& wanted,
                                     const TopicRangesCallback& on_scan) {
  rosbag::Bag bag;
  openBag(bag, in);
  BagRewriteReport report;
  std::string where;
  try {
    std::vector<std::string> chosen;
    for (const std::string& w : wanted)
      chosen.push_back(chooseScanTopic(in, topicsOf(bag), w, kRos1Flavour));
    report.topic = chosen.front();
    rosbag::Bag written;
    written.open(out.string(), rosbag::bagmode::Write);
    rosbag::View all(bag);
    report.connections = all.getConnections().size();
    RawScan scan;
    for (const rosbag::MessageInstance& m : all) {
      where = "topic " + m.getTopic() + ", message " + std::to_string(report.messages);
      if (std::find(chosen.begin(), chosen.end(), m.getTopic()) != chosen.end()) {
        const sensor_msgs::LaserScan::Ptr msg = m.instantiate<sensor_msgs::LaserScan>();
        if (!msg)
          throw InputError(
              in.string(), where,
              "is not a " + std::string(kLaserScanType) + " (type " + m.getDataType() + ")",
              "choose another topic");
        fillRawScan(ros1ScanView(*msg), RosbagConfig{}, scan);
        scan.source_index = report.scans++;
        on_scan(m.getTopic(), msg->ranges, scan);
        written.write(m.getTopic(), m.getTime(), *msg, m.getConnectionHeader());
      } else {
        // the serialised bytes as they are
        written.write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
      }
      ++report.messages;
    }
    written.close();
  } catch (const ros::Exception& e) {
    throw InputError(in.string(), where, std::string("cannot be copied (rosbag: ") + e.what() + ")",
                     "the bag is damaged; repair a copy with `rosbag reindex` or record it again");
  }
  return report;
}

}  // namespace lidarcal::io
