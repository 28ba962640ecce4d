// The only translation unit that includes ROS headers (they are slow to compile and not
// warning-clean; CMake adds them as SYSTEM includes to this library only).

#include "io/import_rosbag.hpp"
#include "io/rosbag_rewrite.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include "common/errors.hpp"
#include "io/pose_track.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;
constexpr const char* kLaserScanType = "sensor_msgs/LaserScan";

void openBag(rosbag::Bag& bag, const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) throw InputError(file.string(), "", "file does not exist", "check the path");
  if (fs::is_directory(file, ec)) throw InputError(file.string(), "", "is a directory, expected a .bag file", "pass the bag file");
  try {
    bag.open(file.string(), rosbag::bagmode::Read);
  } catch (const ros::Exception& e) {
    throw InputError(file.string(), "", std::string("cannot be read as a ROS1 bag (rosbag: ") + e.what() + ")",
                     "a truncated or unindexed bag (recording interrupted) can be repaired on a copy with "
                     "`rosbag reindex`; a ROS2 bag (.db3/.mcap) needs `rosbags-convert` first");
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

std::string describeScanTopics(const std::vector<BagTopic>& topics) {
  std::string text;
  for (const auto& t : topics)
    if (t.datatype == kLaserScanType) text += (text.empty() ? "" : ", ") + t.topic;
  return text.empty() ? "none" : text;
}

std::string chooseTopic(const fs::path& file, const std::vector<BagTopic>& topics, const std::string& wanted) {
  const std::string scan_topics = describeScanTopics(topics);
  if (!wanted.empty()) {
    const auto it = std::find_if(topics.begin(), topics.end(), [&](const BagTopic& t) { return t.topic == wanted; });
    if (it == topics.end())
      throw InputError(file.string(), "--topic " + wanted, "no such topic in the bag (LaserScan topics: " + scan_topics + ")",
                       "pick one with --topic; `lidarcal import --from rosbag1 BAG --list-topics` lists them all");
    if (it->datatype != kLaserScanType)
      throw InputError(file.string(), "--topic " + wanted,
                       "carries " + it->datatype + ", not " + kLaserScanType + " (LaserScan topics: " + scan_topics + ")",
                       "pick a LaserScan topic with --topic");
    return wanted;
  }
  std::vector<std::string> candidates;
  for (const auto& t : topics)
    if (t.datatype == kLaserScanType) candidates.push_back(t.topic);
  if (candidates.empty())
    throw InputError(file.string(), "", std::string("holds no ") + kLaserScanType + " topic",
                     "`lidarcal import --from rosbag1 BAG --list-topics` shows what it holds");
  if (candidates.size() > 1)
    throw InputError(file.string(), "--topic", "the bag has several LaserScan topics (" + scan_topics + ")",
                     "choose one with --topic");
  return candidates.front();
}

/// The importer's view of a LaserScan (pose left as it is).
void fillRawScan(const sensor_msgs::LaserScan& msg, const RosbagConfig& config, RawScan& scan) {
  const std::size_t n = msg.ranges.size();
  scan.ranges_m.assign(msg.ranges.begin(), msg.ranges.end());
  scan.angles_rad.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    scan.angles_rad[i] = static_cast<double>(msg.angle_min) + static_cast<double>(i) * static_cast<double>(msg.angle_increment);
  if (msg.intensities.size() == n) scan.intensities.assign(msg.intensities.begin(), msg.intensities.end());
  else scan.intensities.clear();
  scan.range_min_m = config.range_min_m.value_or(float32Decimal(msg.range_min));
  scan.range_max_m = config.range_max_m.value_or(float32Decimal(msg.range_max));
  scan.stamp_s = msg.header.stamp.toSec();
}

Transform3 toTransform(const geometry_msgs::Point& p, const geometry_msgs::Quaternion& q) {
  Transform3 t;
  t.translation = {p.x, p.y, p.z};
  t.rotation = Eigen::Quaterniond(q.w, q.x, q.y, q.z);
  if (!(t.rotation.norm() > 0.0)) t.rotation = Eigen::Quaterniond::Identity();  // tf's default for an unset quaternion
  t.rotation.normalize();
  return t;
}

Transform3 toTransform(const geometry_msgs::Transform& tf) {
  geometry_msgs::Point p;
  p.x = tf.translation.x;
  p.y = tf.translation.y;
  p.z = tf.translation.z;
  return toTransform(p, tf.rotation);
}

std::string stripSlash(const std::string& frame) { return !frame.empty() && frame.front() == '/' ? frame.substr(1) : frame; }

/// The poses a bag records for config.pose: an odometry track or a tf tree, and the lookups.
class BagPoses {
 public:
  BagPoses(const rosbag::Bag& bag, const fs::path& file, const std::vector<BagTopic>& topics, const BagPoseConfig& config)
      : config_(config) {
    if (config.kind == BagPoseConfig::Kind::none) return;
    auto has = [&](const std::string& name) {
      return std::find_if(topics.begin(), topics.end(), [&](const BagTopic& t) { return t.topic == name; }) != topics.end();
    };
    for (const char* name : {"/tf_static", "/tf"})
      if (has(name) && (config.kind == BagPoseConfig::Kind::tf || std::string(name) == "/tf_static")) readTf(bag, name);
    if (config.kind == BagPoseConfig::Kind::odom) {
      const auto it = std::find_if(topics.begin(), topics.end(), [&](const BagTopic& t) { return t.topic == config.name; });
      if (it == topics.end() || it->datatype != "nav_msgs/Odometry")
        throw InputError(file.string(), "--pose odom:" + config.name,
                         it == topics.end() ? "no such topic in the bag" : "carries " + it->datatype + ", not nav_msgs/Odometry",
                         "`lidarcal import --list-topics BAG` lists the topics and their types");
      for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(config.name))) {
        const nav_msgs::Odometry::ConstPtr o = m.instantiate<nav_msgs::Odometry>();
        if (!o) continue;
        odom_.add(o->header.stamp.toSec(), toTransform(o->pose.pose.position, o->pose.pose.orientation));
        if (odom_child_.empty()) odom_child_ = stripSlash(o->child_frame_id);
      }
      if (odom_.empty())
        throw DataError(file.string(), "--pose odom:" + config.name, "the topic has no odometry message", "choose another --pose");
    } else if (!has("/tf") && !has("/tf_static")) {
      throw InputError(file.string(), "--pose tf:" + config.name, "the bag has neither /tf nor /tf_static",
                       "use --pose odom:TOPIC, or import without --pose");
    }
  }

  /// The sensor's pose at the scan's stamp, or nothing (and why).
  std::optional<Transform3> at(const std::string& frame, double stamp_s, std::string& why) {
    if (config_.kind == BagPoseConfig::Kind::tf) return tree_.lookup(config_.name, frame, stamp_s, config_.hold_s, &why);
    const std::optional<Transform3> base = odom_.at(stamp_s, config_.hold_s);
    if (!base) {
      const auto [first, last] = odom_.span();
      char text[160];
      std::snprintf(text, sizeof text, "at %.3f s: odometry is recorded from %.3f to %.3f s only", stamp_s, first, last);
      why = text;
      return std::nullopt;
    }
    // The sensor's mount on the odometry's child frame, when /tf_static has it.
    std::string unused;
    if (!odom_child_.empty() && frame != odom_child_)
      if (const auto mount = tree_.lookup(odom_child_, frame, stamp_s, config_.hold_s, &unused)) return *base * *mount;
    if (frame != odom_child_ && !odom_child_.empty()) mount_missing_ = true;
    return base;
  }

  /// Notes for the report.
  std::vector<std::string> notes() const {
    std::vector<std::string> n;
    if (config_.kind == BagPoseConfig::Kind::odom)
      n.push_back("VIEWPOINT = odometry " + config_.name + (mount_missing_ ? " (pose of " + odom_child_ +
                                                                                 "; the sensor's mount on it is not in /tf_static)"
                                                                           : " composed with the sensor's mount from /tf_static"));
    if (config_.kind == BagPoseConfig::Kind::tf) n.push_back("VIEWPOINT = the scan frame's pose in " + config_.name + " (/tf, /tf_static)");
    return n;
  }

 private:
  void readTf(const rosbag::Bag& bag, const std::string& topic) {
    const bool is_static = topic == "/tf_static";
    for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(topic))) {
      const tf2_msgs::TFMessage::ConstPtr msg = m.instantiate<tf2_msgs::TFMessage>();  // tf/tfMessage has the same layout
      if (!msg) continue;
      for (const auto& t : msg->transforms) {
        const std::string parent = stripSlash(t.header.frame_id), child = stripSlash(t.child_frame_id);
        if (is_static) tree_.addStatic(parent, child, toTransform(t.transform));
        else tree_.addDynamic(parent, child, t.header.stamp.toSec(), toTransform(t.transform));
      }
    }
  }

  BagPoseConfig config_;
  TransformTrack odom_;
  std::string odom_child_;
  TransformTree tree_;
  bool mount_missing_ = false;
};

}  // namespace

bool rosbagSupported() { return true; }
void requireRosbagSupport(const fs::path&) {}

void RosbagConfig::validate() const {
  checkRangeLimits(range_min_m.value_or(0.0), range_max_m.value_or(std::numeric_limits<double>::infinity()));
}

std::vector<BagTopic> listBagTopics(const fs::path& file) {
  rosbag::Bag bag;
  openBag(bag, file);
  try {
    return topicsOf(bag);
  } catch (const ros::Exception& e) {
    throw InputError(file.string(), "", std::string("the bag index cannot be read (rosbag: ") + e.what() + ")",
                     "repair a copy with `rosbag reindex`");
  }
}

ImportReport readRosbag(const fs::path& file, const RosbagConfig& config, const ScanCallback& on_scan) {
  config.validate();
  rosbag::Bag bag;
  openBag(bag, file);
  ImportReport report;
  std::size_t index = 0;
  std::string topic;
  std::optional<BagPoses> poses;
  StillPoseFilter still(config.pose.still_m, config.pose.still_rad);
  std::size_t without_pose = 0;
  std::string first_why;
  bool upside_down = false;
  try {
    const std::vector<BagTopic> topics = topicsOf(bag);
    topic = chooseTopic(file, topics, config.topic);
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    const std::size_t total = view.size();
    for (const BagTopic& t : topics)
      if (t.topic != topic) report.other_records += t.messages;
    poses.emplace(bag, file, topics, config.pose);
    RawScan scan;  // pose: the identity unless config.pose names a source
    for (const rosbag::MessageInstance& m : view) {
      const sensor_msgs::LaserScan::ConstPtr msg = m.instantiate<sensor_msgs::LaserScan>();
      if (!msg)
        throw InputError(file.string(), "topic " + topic + ", message " + std::to_string(index),
                         "is not a " + std::string(kLaserScanType) + " (type " + m.getDataType() + ")", "choose another topic");
      fillRawScan(*msg, config, scan);
      if (report.sensor_name.empty())
        report.sensor_name = "ROS1 " + std::string(kLaserScanType) + " on " + topic +
                             (msg->header.frame_id.empty() ? "" : " (frame " + msg->header.frame_id + ")");
      scan.source_index = index++;
      scan.progress = total ? static_cast<double>(index) / static_cast<double>(total) : 1.0;
      if (config.pose.kind != BagPoseConfig::Kind::none) {
        std::string why;
        const std::optional<Transform3> pose = poses->at(stripSlash(msg->header.frame_id), scan.stamp_s, why);
        if (!pose) {
          if (first_why.empty()) first_why = why;
          ++without_pose;
          continue;
        }
        upside_down = upside_down || isUpsideDown(*pose);
        scan.pose = still.apply(planarPose(*pose));
      }
      ++report.scans;
      if (!on_scan(scan)) {
        report.stopped_early = true;
        break;
      }
    }
  } catch (const ros::Exception& e) {
    throw InputError(file.string(), topic.empty() ? std::string() : "topic " + topic + ", message " + std::to_string(index),
                     std::string("cannot be read (rosbag: ") + e.what() + ")",
                     "the bag is damaged; repair a copy with `rosbag reindex` or record it again");
  }
  if (report.scans == 0 && without_pose > 0)
    throw DataError(file.string(), "--pose", "no scan of " + topic + " has a pose (" + first_why + ")",
                    "choose another --pose source, or import without --pose");
  if (report.scans == 0)
    throw InputError(file.string(), "topic " + topic, "has no message", "choose another topic with --topic");
  if (config.pose.kind == BagPoseConfig::Kind::none)
    report.notes.push_back("VIEWPOINT = identity for every scan (--pose odom:TOPIC or tf:FRAME reads the bag's poses)");
  if (poses)
    for (const auto& note : poses->notes()) report.notes.push_back(note);
  if (config.pose.kind != BagPoseConfig::Kind::none) {
    char text[200];
    std::snprintf(text, sizeof text, "%zu stops (poses held while they stay within %.3g m and %.3g deg)", still.stops(),
                  config.pose.still_m, config.pose.still_rad * 180.0 / 3.14159265358979323846);
    report.notes.push_back(text);
    if (still.stops() > 1 && 2 * still.stops() > report.scans)
      report.notes.push_back("most stops hold one or two scans: if the sensor stood still, its poses jitter by more than "
                             "that (localisation typically by centimetres): try --still-m 0.05 --still-deg 1");
  }
  if (without_pose > 0)
    report.notes.push_back(std::to_string(without_pose) + " scans skipped without a pose (first: " + first_why + ")");
  if (upside_down)
    report.notes.push_back("the scan frame is upside down in the pose's frame: VIEWPOINT holds the heading of its x axis, "
                           "its beams run clockwise in the world");
  return report;
}

BagRewriteReport rewriteRosbag(const fs::path& in, const fs::path& out, const std::string& wanted,
                               const RangesCallback& on_scan) {
  rosbag::Bag bag;
  openBag(bag, in);
  BagRewriteReport report;
  std::string where;
  try {
    report.topic = chooseTopic(in, topicsOf(bag), wanted);
    rosbag::Bag written;
    written.open(out.string(), rosbag::bagmode::Write);
    rosbag::View all(bag);
    report.connections = all.getConnections().size();
    RawScan scan;
    for (const rosbag::MessageInstance& m : all) {
      where = "topic " + m.getTopic() + ", message " + std::to_string(report.messages);
      if (m.getTopic() == report.topic) {
        const sensor_msgs::LaserScan::Ptr msg = m.instantiate<sensor_msgs::LaserScan>();
        if (!msg)
          throw InputError(in.string(), where, "is not a " + std::string(kLaserScanType) + " (type " + m.getDataType() + ")",
                           "choose another topic");
        fillRawScan(*msg, RosbagConfig{}, scan);
        scan.source_index = report.scans++;
        on_scan(msg->ranges, scan);
        written.write(m.getTopic(), m.getTime(), *msg, m.getConnectionHeader());
      } else {
        written.write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());  // the serialised bytes as they are
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
