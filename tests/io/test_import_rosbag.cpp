// SPDX-License-Identifier: BSD-3-Clause
// ROS1 bag importer, against bags written here with the same ROS libraries (the oracle for
// what a LaserScan says) and, when present, the RPLIDAR recording in ../shared/data.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/String.h>

#include "common/errors.hpp"
#include "import_test_util.hpp"
#include "io/import_rosbag.hpp"
#include "ros/laser_scan_util.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::Collector;
using test::TempDir;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Scan k of n beams: readings 1 + 0.01 i + k metres, intensities i mod 50 when asked.
sensor_msgs::LaserScan laserScan(int k, std::size_t n, bool intensities) {
  return test::laserScanOf(
      ros::Time(100 + k, 5000000), n, 0.0175f,
      [k](std::size_t i) { return 1.0f + 0.01f * static_cast<float>(i) + static_cast<float>(k); },
      intensities ? 50 : 0);
}

/// /scan_a: 5 LaserScans of 12 beams with intensities (some readings invalid); /scan_b: 3
/// LaserScans of 8 beams without; /chatter: 2 strings.
std::filesystem::path writeBag(const TempDir& dir) {
  const auto file = dir / "test.bag";
  rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
  for (int k = 0; k < 5; ++k) {
    sensor_msgs::LaserScan m = laserScan(k, 12, true);
    m.ranges[1] = kInf;
    m.ranges[2] = kNaN;
    m.ranges[3] = 0.1f;   // below range_min
    m.ranges[4] = 12.5f;  // above range_max
    bag.write("/scan_a", m.header.stamp, m);
    if (k < 3) {
      const sensor_msgs::LaserScan b = laserScan(k, 8, false);
      bag.write("/scan_b", b.header.stamp, b);
    }
    if (k < 2) {
      std_msgs::String s;
      s.data = "hello";
      bag.write("/chatter", ros::Time(100 + k, 1), s);
    }
  }
  bag.close();
  return file;
}

void expectErrorMentions(const std::function<void()>& f, const std::vector<std::string>& parts) {
  try {
    f();
    FAIL() << "no error";
  } catch (const InputError& e) {
    for (const auto& p : parts)
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what() << "\nmissing: " << p;
    EXPECT_FALSE(e.remedy().empty());
  }
}

TEST(RosbagImport, ThisBuildSupportsBags) { EXPECT_TRUE(rosbagSupported()); }

TEST(RosbagImport, ListsTopicsWithTypesAndCounts) {
  TempDir dir;
  const auto topics = listBagTopics(writeBag(dir));
  ASSERT_EQ(topics.size(), 3u);
  EXPECT_EQ(topics[0].topic, "/chatter");
  EXPECT_EQ(topics[0].datatype, "std_msgs/String");
  EXPECT_EQ(topics[0].messages, 2u);
  EXPECT_EQ(topics[1].topic, "/scan_a");
  EXPECT_EQ(topics[1].datatype, "sensor_msgs/LaserScan");
  EXPECT_EQ(topics[1].messages, 5u);
  EXPECT_EQ(topics[2].messages, 3u);
}

TEST(RosbagImport, AnglesRangesLimitsIntensitiesAndIdentityPoseOfTheChosenTopic) {
  TempDir dir;
  const auto bag = writeBag(dir);
  RosbagConfig c;
  c.topic = "/scan_a";
  Collector got;
  const ImportReport r = readRosbag(bag, c, got.callback());
  EXPECT_EQ(r.scans, 5u);
  EXPECT_EQ(r.other_records, 5u);  // 3 on /scan_b, 2 on /chatter
  ASSERT_EQ(got.scans.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    SCOPED_TRACE(k);
    const RawScan& s = got.scans[static_cast<std::size_t>(k)];
    const sensor_msgs::LaserScan m = laserScan(k, 12, true);
    ASSERT_EQ(s.ranges_m.size(), 12u);
    for (std::size_t i = 0; i < 12; ++i) {
      EXPECT_DOUBLE_EQ(s.angles_rad[i], static_cast<double>(m.angle_min) +
                                            static_cast<double>(i) * m.angle_increment);
      if (i >= 5) {
        EXPECT_EQ(s.ranges_m[i], m.ranges[i]);
      }
      EXPECT_EQ(s.intensities[i], m.intensities[i]);
    }
    EXPECT_TRUE(std::isinf(s.ranges_m[1]));
    EXPECT_TRUE(std::isnan(s.ranges_m[2]));
    EXPECT_DOUBLE_EQ(s.range_min_m, 0.15);  // the float 0.15f as the decimal it was written as
    EXPECT_DOUBLE_EQ(s.range_max_m, 12.0);
    EXPECT_DOUBLE_EQ(s.pose.x_m, 0.0);
    EXPECT_DOUBLE_EQ(s.pose.y_m, 0.0);
    EXPECT_DOUBLE_EQ(s.pose.yaw_rad, 0.0);
    EXPECT_NEAR(s.stamp_s, 100.005 + k, 1e-9);
  }
  EXPECT_NE(r.sensor_name.find("/scan_a"), std::string::npos);
}

TEST(RosbagImport, TopicWithoutIntensitiesAndRangeOverrides) {
  TempDir dir;
  RosbagConfig c;
  c.topic = "/scan_b";
  c.range_min_m = 0.5;
  c.range_max_m = 6.0;
  Collector got;
  readRosbag(writeBag(dir), c, got.callback());
  ASSERT_EQ(got.scans.size(), 3u);
  EXPECT_TRUE(got.scans[0].intensities.empty());
  EXPECT_DOUBLE_EQ(got.scans[0].range_min_m, 0.5);
  EXPECT_DOUBLE_EQ(got.scans[0].range_max_m, 6.0);
}

TEST(RosbagImport, TopicErrorsNameTheTopicAndTheCandidates) {
  TempDir dir;
  const auto bag = writeBag(dir);
  Collector got;
  expectErrorMentions([&] { readRosbag(bag, {}, got.callback()); },
                      {"several LaserScan topics", "/scan_a", "/scan_b", "--topic"});
  RosbagConfig missing;
  missing.topic = "/scan";
  expectErrorMentions(
      [&] { readRosbag(bag, missing, got.callback()); },
      {bag.string(), "--topic /scan", "no such topic", "/scan_a, /scan_b", "--list-topics"});
  RosbagConfig wrong_type;
  wrong_type.topic = "/chatter";
  expectErrorMentions([&] { readRosbag(bag, wrong_type, got.callback()); },
                      {"/chatter", "std_msgs/String"});
  EXPECT_TRUE(got.scans.empty());
}

TEST(RosbagImport, TruncatedOrForeignFilesAreClearErrors) {
  TempDir dir;
  const std::string bytes = test::readFile(writeBag(dir));
  for (std::size_t keep : {bytes.size() / 2, bytes.size() - 10, std::size_t{100}}) {
    SCOPED_TRACE(keep);
    test::writeFile(dir / "cut.bag", bytes.substr(0, keep));
    Collector got;
    expectErrorMentions([&] { readRosbag(dir / "cut.bag", {}, got.callback()); },
                        {"cut.bag", "rosbag reindex"});
  }
  test::writeFile(dir / "text.bag", "not a bag at all\n");
  Collector got;
  expectErrorMentions([&] { listBagTopics(dir / "text.bag"); },
                      {"text.bag", "cannot be read as a ROS1 bag"});
  expectErrorMentions([&] { readRosbag(dir / "missing.bag", {}, got.callback()); },
                      {"does not exist"});
}

TEST(RosbagImport, RplidarRecordingMatchesTheMessages) {
  const auto bag_file = test::sharedData() / "rplidar_a2_room/rplidar_1.bag";
  if (!std::filesystem::exists(bag_file)) GTEST_SKIP() << "shared data absent: " << bag_file;
  Collector got;
  // the bag's only LaserScan topic
  const ImportReport r = readRosbag(bag_file, {}, got.callback());
  ASSERT_EQ(r.scans, 1319u);
  // Oracle: the messages as the ROS library deserialises them.
  rosbag::Bag bag(bag_file.string(), rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery("/scan_rplidar"));
  std::size_t k = 0;
  for (const rosbag::MessageInstance& m : view) {
    const auto msg = m.instantiate<sensor_msgs::LaserScan>();
    const RawScan& s = got.scans[k++];
    ASSERT_EQ(s.ranges_m.size(), 360u);
    ASSERT_EQ(msg->ranges.size(), 360u);
    for (std::size_t i : {0u, 1u, 90u, 179u, 270u, 359u}) {
      EXPECT_EQ(s.angles_rad[i], static_cast<double>(msg->angle_min) +
                                     static_cast<double>(i) * msg->angle_increment);
      EXPECT_EQ(s.ranges_m[i], msg->ranges[i]);
      EXPECT_EQ(s.intensities[i], msg->intensities[i]);
    }
  }
  EXPECT_EQ(k, 1319u);
  // 360 beams at 1 degree cover the full circle.
  EXPECT_NEAR(got.scans[0].angles_rad[359] - got.scans[0].angles_rad[0], deg2rad(359), 1e-4);
}

}  // namespace
}  // namespace lidarcal::io
