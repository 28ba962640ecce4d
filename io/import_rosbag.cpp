// The only translation unit that includes ROS headers (they are slow to compile and not
// warning-clean; CMake adds them as SYSTEM includes to this library only).

#include "io/import_rosbag.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>

#include "common/errors.hpp"

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

/// A float32 limit as the decimal it was written as (0.15f -> 0.15, not 0.15000000596...):
/// seven significant digits are what a float holds.
double decimalOf(float value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.7g", static_cast<double>(value));
  return std::strtod(text, nullptr);
}

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
  try {
    const std::vector<BagTopic> topics = topicsOf(bag);
    topic = chooseTopic(file, topics, config.topic);
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    const std::size_t total = view.size();
    for (const BagTopic& t : topics)
      if (t.topic != topic) report.other_records += t.messages;
    RawScan scan;  // pose stays the identity: the bag's odometry is not read
    for (const rosbag::MessageInstance& m : view) {
      const sensor_msgs::LaserScan::ConstPtr msg = m.instantiate<sensor_msgs::LaserScan>();
      if (!msg)
        throw InputError(file.string(), "topic " + topic + ", message " + std::to_string(index),
                         "is not a " + std::string(kLaserScanType) + " (type " + m.getDataType() + ")", "choose another topic");
      const std::size_t n = msg->ranges.size();
      scan.ranges_m.assign(msg->ranges.begin(), msg->ranges.end());
      scan.angles_rad.resize(n);
      for (std::size_t i = 0; i < n; ++i)
        scan.angles_rad[i] = static_cast<double>(msg->angle_min) + static_cast<double>(i) * static_cast<double>(msg->angle_increment);
      if (msg->intensities.size() == n) scan.intensities.assign(msg->intensities.begin(), msg->intensities.end());
      else scan.intensities.clear();
      scan.range_min_m = config.range_min_m.value_or(decimalOf(msg->range_min));
      scan.range_max_m = config.range_max_m.value_or(decimalOf(msg->range_max));
      scan.stamp_s = msg->header.stamp.toSec();
      if (report.sensor_name.empty())
        report.sensor_name = "ROS1 " + std::string(kLaserScanType) + " on " + topic +
                             (msg->header.frame_id.empty() ? "" : " (frame " + msg->header.frame_id + ")");
      scan.source_index = index++;
      scan.progress = total ? static_cast<double>(index) / static_cast<double>(total) : 1.0;
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
  if (report.scans == 0)
    throw InputError(file.string(), "topic " + topic, "has no message", "choose another topic with --topic");
  report.notes.push_back("VIEWPOINT = identity for every scan (the bag's odometry is not read)");
  return report;
}

}  // namespace lidarcal::io
