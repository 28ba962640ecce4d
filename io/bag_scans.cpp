// SPDX-License-Identifier: BSD-3-Clause
#include "io/bag_scans.hpp"

#include <algorithm>
#include <cstdio>

#include "common/errors.hpp"
#include "common/plural.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;

const BagTopic* findTopic(const std::vector<BagTopic>& topics, const std::string& name) {
  const auto it = std::find_if(topics.begin(), topics.end(),
                               [&](const BagTopic& t) { return t.topic == name; });
  return it == topics.end() ? nullptr : &*it;
}

std::string describeScanTopics(const std::vector<BagTopic>& topics, const BagFlavour& flavour) {
  std::string text;
  for (const auto& t : topics)
    if (t.datatype == flavour.scan_type) text += (text.empty() ? "" : ", ") + t.topic;
  return text.empty() ? "none" : text;
}

std::string listTopicsHint(const BagFlavour& flavour) {
  return std::string("`lidarcal import --from ") + flavour.from +
         " BAG --list-topics` lists them all";
}

}  // namespace

void RosbagConfig::validate() const {
  checkRangeLimits(range_min_m.value_or(0.0),
                   range_max_m.value_or(std::numeric_limits<double>::infinity()));
}

Transform3 makeTransform(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation) {
  Transform3 t;
  t.translation = translation;
  t.rotation = rotation;
  // tf's default for an unset quaternion
  if (!(t.rotation.norm() > 0.0)) t.rotation = Eigen::Quaterniond::Identity();
  t.rotation.normalize();
  return t;
}

std::string stripSlash(const std::string& frame) {
  return !frame.empty() && frame.front() == '/' ? frame.substr(1) : frame;
}

std::string chooseScanTopic(const fs::path& file, const std::vector<BagTopic>& topics,
                            const std::string& wanted, const BagFlavour& flavour) {
  const std::string scan_topics = describeScanTopics(topics, flavour);
  if (!wanted.empty()) {
    const BagTopic* t = findTopic(topics, wanted);
    if (!t)
      throw InputError(file.string(), "--topic " + wanted,
                       "no such topic in the bag (LaserScan topics: " + scan_topics + ")",
                       "pick one with --topic; " + listTopicsHint(flavour));
    if (t->datatype != flavour.scan_type)
      throw InputError(file.string(), "--topic " + wanted,
                       "carries " + t->datatype + ", not " + flavour.scan_type +
                           " (LaserScan topics: " + scan_topics + ")",
                       "pick a LaserScan topic with --topic");
    return wanted;
  }
  std::vector<std::string> candidates;
  for (const auto& t : topics)
    if (t.datatype == flavour.scan_type) candidates.push_back(t.topic);
  if (candidates.empty())
    throw InputError(file.string(), "", std::string("holds no ") + flavour.scan_type + " topic",
                     std::string("`lidarcal import --from ") + flavour.from +
                         " BAG --list-topics` shows what it holds");
  if (candidates.size() > 1)
    throw InputError(file.string(), "--topic",
                     "the bag has several LaserScan topics (" + scan_topics + ")",
                     "choose one with --topic");
  return candidates.front();
}

namespace {

/// Throws InputError naming `option` unless the bag has `name` carrying `type`.
void requireTopicType(const fs::path& file, const std::vector<BagTopic>& topics,
                      const std::string& name, const char* type, const std::string& option) {
  const BagTopic* t = findTopic(topics, name);
  if (!t || t->datatype != type)
    throw InputError(file.string(), option,
                     !t ? "no such topic in the bag" : "carries " + t->datatype + ", not " + type,
                     "`lidarcal import --list-topics BAG` lists the topics and their types");
}

}  // namespace

std::vector<std::string> poseTopics(const fs::path& file, const std::vector<BagTopic>& topics,
                                    const BagPoseConfig& config, const BagFlavour& flavour) {
  std::vector<std::string> read;
  if (config.kind == BagPoseConfig::Kind::none) {
    // mountings
    if (!config.vehicle_frame.empty() && findTopic(topics, "/tf_static"))
      read.emplace_back("/tf_static");
    return read;
  }
  for (const char* name : {"/tf_static", "/tf"})
    if (findTopic(topics, name) &&
        (config.kind == BagPoseConfig::Kind::tf || std::string(name) == "/tf_static"))
      read.emplace_back(name);
  if (config.kind == BagPoseConfig::Kind::odom) {
    requireTopicType(file, topics, config.name, flavour.odom_type, "--pose odom:" + config.name);
    read.push_back(config.name);
  } else if (read.empty()) {
    throw InputError(file.string(), "--pose tf:" + config.name,
                     "the bag has neither /tf nor /tf_static",
                     "use --pose odom:TOPIC, or import without --pose");
  }
  return read;
}

void checkWheelTopic(const fs::path& file, const std::vector<BagTopic>& topics,
                     const WheelJoints& joints, const BagFlavour& flavour) {
  requireTopicType(file, topics, joints.topic, flavour.joint_type, "--wheels " + joints.topic);
}

void fillRawScan(const LaserScanView& msg, const RosbagConfig& config, RawScan& scan) {
  const std::size_t n = msg.count;
  scan.ranges_m.assign(msg.ranges, msg.ranges + n);
  scan.angles_rad.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    scan.angles_rad[i] = static_cast<double>(msg.angle_min) +
                         static_cast<double>(i) * static_cast<double>(msg.angle_increment);
  if (msg.intensity_count == n && n > 0)
    scan.intensities.assign(msg.intensities, msg.intensities + n);
  else
    scan.intensities.clear();
  scan.range_min_m = config.range_min_m.value_or(float32Decimal(msg.range_min));
  scan.range_max_m = config.range_max_m.value_or(float32Decimal(msg.range_max));
  // As ros::Time::toSec and rclcpp::Time::seconds: sec + 1e-9 nanosec.
  scan.stamp_s = static_cast<double>(msg.stamp_sec) + 1e-9 * static_cast<double>(msg.stamp_nanosec);
}

void BagPoses::addOdometry(double stamp_s, const Transform3& pose, const std::string& child_frame) {
  odom_.add(stamp_s, pose);
  if (odom_child_.empty()) odom_child_ = stripSlash(child_frame);
}

void BagPoses::addTransform(const std::string& parent, const std::string& child, double stamp_s,
                            const Transform3& t, bool is_static) {
  if (is_static)
    tree_.addStatic(stripSlash(parent), stripSlash(child), t);
  else
    tree_.addDynamic(stripSlash(parent), stripSlash(child), stamp_s, t);
}

void BagPoses::checkFilled(const fs::path& file) const {
  if (config_.kind == BagPoseConfig::Kind::odom && odom_.empty())
    throw DataError(file.string(), "--pose odom:" + config_.name,
                    "the topic has no odometry message", "choose another --pose");
}

std::optional<Transform3> BagPoses::at(const std::string& frame, double stamp_s, std::string& why,
                                       bool* mount_missing) {
  if (mount_missing) *mount_missing = false;
  if (config_.kind == BagPoseConfig::Kind::tf)
    return tree_.lookup(config_.name, frame, stamp_s, config_.hold_s, &why);
  if (odom_.empty()) {
    why = "no odometry message on " + config_.name + " yet";
    return std::nullopt;
  }
  const std::optional<Transform3> base = odom_.at(stamp_s, config_.hold_s);
  if (!base) {
    const auto [first, last] = odom_.span();
    char text[160];
    std::snprintf(text, sizeof text, "at %.3f s: odometry is recorded from %.3f to %.3f s only",
                  stamp_s, first, last);
    why = text;
    return std::nullopt;
  }
  // The sensor's mount on the odometry's child frame, when /tf_static has it.
  std::string unused;
  if (!odom_child_.empty() && frame != odom_child_)
    if (const auto mount = tree_.lookup(odom_child_, frame, stamp_s, config_.hold_s, &unused))
      return *base * *mount;
  if (frame != odom_child_ && !odom_child_.empty()) {
    mount_missing_ = true;
    if (mount_missing) *mount_missing = true;
  }
  return base;
}

std::vector<std::string> BagPoses::notes() const {
  std::vector<std::string> n;
  if (config_.kind == BagPoseConfig::Kind::odom)
    n.push_back("VIEWPOINT = odometry " + config_.name +
                (mount_missing_ ? " (pose of " + odom_child_ +
                                      "; the sensor's mount on it is not in /tf_static)"
                                : " composed with the sensor's mount from /tf_static"));
  if (config_.kind == BagPoseConfig::Kind::tf)
    n.push_back("VIEWPOINT = the scan frame's pose in " + config_.name + " (/tf, /tf_static)");
  return n;
}

void BagPoses::addRigPoses(const std::string& frame, double stamp_s, RawScan& scan) const {
  scan.frame_id = frame;
  scan.vehicle_frame = config_.vehicle_frame == "auto" ? tree_.vehicleFrameOf(frame)
                                                       : stripSlash(config_.vehicle_frame);
  scan.mounting.reset();
  scan.vehicle_pose.reset();
  if (const auto m = tree_.lookup(scan.vehicle_frame, frame, stamp_s, config_.hold_s)) {
    const Pose2 p = planarPose(*m);
    scan.mounting = Mounting{p.x_m, p.y_m, p.yaw_rad, isUpsideDown(*m), m->translation.z()};
  }
  std::optional<Transform3> vehicle;
  if (config_.kind == BagPoseConfig::Kind::tf)
    vehicle = tree_.lookup(config_.name, scan.vehicle_frame, stamp_s, config_.hold_s);
  if (config_.kind == BagPoseConfig::Kind::odom) {
    vehicle = odom_.at(stamp_s, config_.hold_s);
    if (vehicle && !odom_child_.empty() && odom_child_ != scan.vehicle_frame) {
      const auto link = tree_.lookup(odom_child_, scan.vehicle_frame, stamp_s, config_.hold_s);
      vehicle = link ? std::optional<Transform3>(*vehicle * *link) : std::nullopt;
    }
  }
  if (vehicle) scan.vehicle_pose = planarPose(*vehicle);
}

BagScanSink::BagScanSink(const BagPoseConfig& config, BagPoses& poses, const ScanCallback& on_scan,
                         ImportReport& report)
    : config_(config),
      poses_(poses),
      on_scan_(on_scan),
      report_(report),
      still_(config.still_m, config.still_rad) {}

bool BagScanSink::offer(RawScan& scan, const std::string& frame_id) {
  if (config_.kind != BagPoseConfig::Kind::none) {
    std::string why;
    const std::optional<Transform3> pose = poses_.at(stripSlash(frame_id), scan.stamp_s, why);
    if (!pose) {
      if (first_why_.empty()) first_why_ = why;
      ++without_pose_;
      return true;
    }
    upside_down_ = upside_down_ || isUpsideDown(*pose);
    scan.pose = still_.apply(planarPose(*pose));
  }
  if (!config_.vehicle_frame.empty()) poses_.addRigPoses(stripSlash(frame_id), scan.stamp_s, scan);
  ++report_.scans;
  if (on_scan_(scan)) return true;
  report_.stopped_early = true;
  return false;
}

std::string shortStopsAdvice() {
  return "if the sensor stood still, its poses jitter by more than that (localisation typically "
         "by centimetres): try --still-m 0.05 --still-deg 1";
}

void BagScanSink::finish(const fs::path& file, const std::string& topic) {
  if (report_.scans == 0 && without_pose_ > 0)
    throw DataError(file.string(), "--pose",
                    "no scan of " + topic + " has a pose (" + first_why_ + ")",
                    "choose another --pose source, or import without --pose");
  if (report_.scans == 0)
    throw InputError(file.string(), "topic " + topic, "has no message",
                     "choose another topic with --topic");
  if (config_.kind == BagPoseConfig::Kind::none)
    report_.notes.push_back(
        "VIEWPOINT = identity for every scan (--pose odom:TOPIC or tf:FRAME reads the bag's "
        "poses)");
  for (const auto& note : poses_.notes()) report_.notes.push_back(note);
  if (config_.kind != BagPoseConfig::Kind::none)
    report_.short_stops = still_.stops() > 1 && 2 * still_.stops() > report_.scans;
  // A rig import reports the vehicle's stops over all its topics itself.
  if (config_.kind != BagPoseConfig::Kind::none && config_.vehicle_frame.empty()) {
    char text[200];
    std::snprintf(
        text, sizeof text, "%zu stops (poses held while they stay within %.3g m and %.3g deg)",
        still_.stops(), config_.still_m, config_.still_rad * 180.0 / 3.14159265358979323846);
    report_.notes.push_back(text);
    if (report_.short_stops)
      report_.notes.push_back("most stops hold one or two scans: " + shortStopsAdvice());
  }
  if (without_pose_ > 0)
    report_.notes.push_back(plural(without_pose_, "scan") +
                            " skipped without a pose (first: " + first_why_ + ")");
  if (upside_down_)
    report_.notes.push_back(
        "the scan frame is upside down in the pose's frame: VIEWPOINT holds the heading of its x "
        "axis, "
        "its beams run clockwise in the world");
}

}  // namespace lidarcal::io
