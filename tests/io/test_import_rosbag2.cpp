// SPDX-License-Identifier: BSD-3-Clause
// ROS 2 bag importer (MCAP, SQLite .db3, rosbag2 directories; CDR LaserScan), against bags
// written here from the specifications (rosbag2_test_writer.hpp): the points of the imported
// sequence must be what the test computes from the ranges it chose. Needs no ROS.

#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "import_test_util.hpp"
#include "io/cdr.hpp"
#include "io/detect_format.hpp"
#include "io/import_rosbag2.hpp"
#include "io/pcd_scan.hpp"
#include "io/ros2_msgs.hpp"
#include "io/sequence.hpp"
#include "rosbag2_test_writer.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;
using namespace std::string_literals;
using test::Collector;
using test::TempDir;
using test::TestScan;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr std::size_t kBeams = 9;

/// Scan k of /scan: stamp 100 + k s + 0.5 s; beams with no return (NaN, +-inf, 0, negative), one
/// below range_min, one above range_max, the rest valid and different per scan.
TestScan scanA(int k) {
  TestScan s;
  s.sec = 100 + k;
  s.nanosec = 500000000;
  s.ranges = {1.0f + 0.1f * static_cast<float>(k), kNaN, kInf, -kInf, 0.0f, 0.05f, 20.0f, 3.25f,
              11.5f - static_cast<float>(k)};
  for (std::size_t i = 0; i < kBeams; ++i)
    s.intensities.push_back(static_cast<float>(10 * k + static_cast<int>(i)));
  return s;
}

/// Scan k of /scan_b: 4 beams, no intensities, another frame.
TestScan scanB(int k) {
  TestScan s;
  s.sec = 200 + k;
  s.frame_id = "laser_b";
  s.angle_min = 0.0f;
  s.angle_increment = 0.5f;
  s.ranges = {2.0f, 2.5f, 3.0f + static_cast<float>(k), 4.0f};
  return s;
}

/// What a sequence must hold for a scan: x = r cos a, y = r sin a for readings inside
/// [range_min, range_max], NaN for the others (the test's own rule, docs/FORMAT.md).
void expectPoints(const Scan& got, const TestScan& want) {
  ASSERT_EQ(got.cloud->size(), want.ranges.size());
  for (std::size_t i = 0; i < want.ranges.size(); ++i) {
    SCOPED_TRACE(i);
    const double r = want.ranges[i];
    const double a = static_cast<double>(want.angle_min) +
                     static_cast<double>(i) * static_cast<double>(want.angle_increment);
    const auto& p = got.cloud->points[i];
    if (std::isfinite(r) && r > 0 && r >= 0.15 && r <= 12.0) {
      EXPECT_NEAR(p.x, r * std::cos(a), 2e-6);
      EXPECT_NEAR(p.y, r * std::sin(a), 2e-6);
    } else {
      EXPECT_TRUE(std::isnan(p.x) && std::isnan(p.y)) << p.x << " " << p.y;
    }
    if (!want.intensities.empty()) {
      EXPECT_EQ(p.intensity, want.intensities[i]);
    }
  }
}

/// `lidarcal import -q ARGS -o OUT` succeeds and scan k of OUT holds the points of want(k).
void importAndExpectPoints(const std::string& args, const fs::path& out, TestScan (*want)(int),
                           std::size_t scans) {
  const auto r = test::runCli("import -q " + args + " -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Sequence seq = openSequence(out);
  ASSERT_EQ(seq.scans.size(), scans);
  for (std::size_t k = 0; k < scans; ++k) {
    SCOPED_TRACE(k);
    expectPoints(readScan(seq.scans[k].path), want(static_cast<int>(k)));
  }
}

struct McapCase {
  std::string first, second;  // compressions of the two chunks
  bool big_endian;
};
void PrintTo(const McapCase& c, std::ostream* os) {
  *os << "'" << c.first << "' + '" << c.second << "'" << (c.big_endian ? " big-endian" : "");
}

/// /scan: scans 0..5 in two chunks with interleaved log times (even k in the first chunk, odd k
/// in the second, each chunk's in reverse time order), scan 6 as a message outside chunks;
/// /scan_b: 3 scans; /chatter: 2 strings.
std::string mcapBag(const McapCase& c) {
  using namespace test;
  const auto t = [](int k) { return std::uint64_t{1000} + 10u * static_cast<unsigned>(k); };
  std::string a = schemaRecord(1, "sensor_msgs/msg/LaserScan") + channelRecord(1, 1, "/scan") +
                  channelRecord(3, 1, "/scan_b");
  std::string b = schemaRecord(2, "std_msgs/msg/String") + channelRecord(2, 2, "/chatter");
  for (int k = 5; k >= 0; --k)
    (k % 2 ? b : a) += messageRecord(1, t(k), laserScanCdr(scanA(k), c.big_endian));
  for (int k = 0; k < 3; ++k) a += messageRecord(3, t(k) + 1, laserScanCdr(scanB(k), c.big_endian));
  b += messageRecord(2, 1001, "\0\1\0\0\3\0\0\0hi\0"s) +
       messageRecord(2, 1051, "\0\1\0\0\3\0\0\0hi\0"s);
  return mcapHead() + chunkRecord(a, c.first, t(0), t(4)) + chunkRecord(b, c.second, t(1), 1051) +
         messageRecord(1, t(6), laserScanCdr(scanA(6), c.big_endian)) + mcapTail();
}

class Rosbag2Mcap : public ::testing::TestWithParam<McapCase> {};

TEST_P(Rosbag2Mcap, ScansInLogTimeOrderWithTheTestsRangesAnglesAndLimits) {
  TempDir dir;
  const fs::path bag = dir / "bag.mcap";
  test::writeFile(bag, mcapBag(GetParam()));
  RosbagConfig config;
  config.topic = "/scan";
  Collector got;
  const ImportReport r = readRosbag2(bag, config, got.callback());
  EXPECT_EQ(r.scans, 7u);
  EXPECT_EQ(r.other_records, 5u);  // 3 on /scan_b, 2 on /chatter
  EXPECT_EQ(r.sensor_name, "ROS 2 sensor_msgs/msg/LaserScan on /scan (frame laser)");
  ASSERT_EQ(got.scans.size(), 7u);
  for (int k = 0; k < 7; ++k) {
    SCOPED_TRACE(k);
    const RawScan& s = got.scans[static_cast<std::size_t>(k)];
    const TestScan want = scanA(k);
    ASSERT_EQ(s.ranges_m.size(), kBeams);
    for (std::size_t i = 0; i < kBeams; ++i) {
      EXPECT_EQ(std::isnan(s.ranges_m[i]), std::isnan(want.ranges[i]));
      if (!std::isnan(want.ranges[i])) {
        EXPECT_EQ(s.ranges_m[i], want.ranges[i]);
      }
      EXPECT_EQ(s.angles_rad[i],
                static_cast<double>(want.angle_min) +
                    static_cast<double>(i) * static_cast<double>(want.angle_increment));
      EXPECT_EQ(s.intensities[i], want.intensities[i]);
    }
    EXPECT_DOUBLE_EQ(s.range_min_m, 0.15);  // the float 0.15f as the decimal it was written as
    EXPECT_DOUBLE_EQ(s.range_max_m, 12.0);
    EXPECT_NEAR(s.stamp_s, 100.5 + k, 1e-9);
    EXPECT_EQ(s.source_index, static_cast<std::size_t>(k));
  }
}

TEST_P(Rosbag2Mcap, TheCommandWritesThePointsTheTestComputes) {
  TempDir dir;
  const fs::path bag = dir / "recording";  // no extension: the content decides
  test::writeFile(bag, mcapBag(GetParam()));
  importAndExpectPoints(bag.string() + " --topic /scan", dir / "seq", scanA, 7);
  importAndExpectPoints("--from rosbag2 " + bag.string() + " --topic /scan_b", dir / "seq_b", scanB,
                        3);
}

INSTANTIATE_TEST_SUITE_P(
    Compressions, Rosbag2Mcap,
    ::testing::Values(McapCase{"", "zstd", false}, McapCase{"zstd", "lz4", false},
                      McapCase{"lz4", "", false}, McapCase{"zstd", "lz4", true}),
    [](const ::testing::TestParamInfo<McapCase>& p) {
      auto name = [](const std::string& c) { return c.empty() ? std::string("none") : c; };
      return name(p.param.first) + "_" + name(p.param.second) +
             (p.param.big_endian ? "_big_endian" : "");
    });

TEST(Rosbag2McapTopics, ListsTopicsWithTypesAndCounts) {
  TempDir dir;
  test::writeFile(dir / "bag.mcap", mcapBag({"zstd", "lz4", false}));
  const auto topics = listRosbag2Topics(dir / "bag.mcap");
  ASSERT_EQ(topics.size(), 3u);
  EXPECT_EQ(topics[0].topic, "/chatter");
  EXPECT_EQ(topics[0].datatype, "std_msgs/msg/String");
  EXPECT_EQ(topics[0].messages, 2u);
  EXPECT_EQ(topics[1].topic, "/scan");
  EXPECT_EQ(topics[1].datatype, "sensor_msgs/msg/LaserScan");
  EXPECT_EQ(topics[1].messages, 7u);
  EXPECT_EQ(topics[2].messages, 3u);
  const auto r =
      test::runCli("import --from rosbag2 " + (dir / "bag.mcap").string() + " --list-topics");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| /scan | sensor_msgs/msg/LaserScan | 7 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| /chatter | std_msgs/msg/String | 2 |"), std::string::npos) << r.out;
}

TEST(Rosbag2McapTopics, SeveralScanTopicsWithoutTopicIsAnErrorNamingThem) {
  TempDir dir;
  test::writeFile(dir / "bag.mcap", mcapBag({"", "", false}));
  try {
    readRosbag2(dir / "bag.mcap", RosbagConfig{}, Collector{}.callback());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/scan, /scan_b"), std::string::npos) << e.what();
  }
}

/// Scans one per second from stamp 100.5; odometry from 100 to 107 s moving 1 m/s along x.
std::string mcapWithOdometry() {
  using namespace test;
  std::string records = schemaRecord(1, "sensor_msgs/msg/LaserScan") +
                        channelRecord(1, 1, "/scan") + schemaRecord(2, "nav_msgs/msg/Odometry") +
                        channelRecord(2, 2, "/odom");
  for (int k = 0; k <= 7; ++k)
    records += messageRecord(2, 100 * k, odometryCdr(100 + k, 0, k, 0.0, 0.0, k % 2 == 1));
  for (int k = 0; k < 5; ++k) records += messageRecord(1, 100 * k + 50, laserScanCdr(scanA(k)));
  return mcapHead() + chunkRecord(records, "zstd", 0, 750) + mcapTail();
}

RosbagConfig withPose(BagPoseConfig::Kind kind, const std::string& name) {
  RosbagConfig config;
  config.pose.kind = kind;
  config.pose.name = name;
  return config;
}

TEST(Rosbag2Pose, OdometryGivesEachScanTheInterpolatedPose) {
  TempDir dir;
  test::writeFile(dir / "bag.mcap", mcapWithOdometry());
  RosbagConfig config = withPose(BagPoseConfig::Kind::odom, "/odom");
  Collector got;
  const ImportReport r = readRosbag2(dir / "bag.mcap", config, got.callback());
  ASSERT_EQ(got.scans.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(got.scans[static_cast<std::size_t>(k)].pose.x_m, k + 0.5, 1e-9);
    EXPECT_NEAR(got.scans[static_cast<std::size_t>(k)].pose.yaw_rad, 0.0, 1e-12);
  }
  EXPECT_EQ(r.other_records, 8u);
  const auto cli = test::runCli("import -q " + (dir / "bag.mcap").string() +
                                " --pose odom:/odom -o " + (dir / "seq").string());
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_NEAR(readScanHeader(openSequence(dir / "seq").scans[3].path).viewpoint.x_m, 3.5, 1e-6);
  config.pose.name = "/scan";
  // not an Odometry topic
  EXPECT_THROW(readRosbag2(dir / "bag.mcap", config, Collector{}.callback()), InputError);
}

/// Scans 0..4 in frame "laser", mounted on base_link 0.2 m ahead and turned by 90 degrees
/// (/tf_static); base_link in map moves 1 m/s along y (/tf, samples 100..107 s).
std::string mcapWithTf() {
  using namespace test;
  std::string records = schemaRecord(1, "sensor_msgs/msg/LaserScan") +
                        channelRecord(1, 1, "/scan") + schemaRecord(2, "tf2_msgs/msg/TFMessage") +
                        channelRecord(2, 2, "/tf") + channelRecord(3, 2, "/tf_static");
  records += messageRecord(3, 0, tfMessageCdr({{100, "base_link", "laser", 0.2, 0.0, M_PI / 2}}));
  for (int k = 0; k <= 7; ++k)
    records += messageRecord(
        2, 100 * k,
        tfMessageCdr({{100 + k, "map", "base_link", 0.0, static_cast<double>(k), 0.0}},
                     k % 2 == 1));
  for (int k = 0; k < 5; ++k) records += messageRecord(1, 100 * k + 50, laserScanCdr(scanA(k)));
  return mcapHead() + chunkRecord(records, "lz4", 0, 750) + mcapTail();
}

TEST(Rosbag2Pose, TfChainGivesTheScanFramesPoseInTheFixedFrame) {
  TempDir dir;
  test::writeFile(dir / "bag.mcap", mcapWithTf());
  RosbagConfig config = withPose(BagPoseConfig::Kind::tf, "map");
  Collector got;
  readRosbag2(dir / "bag.mcap", config, got.callback());
  ASSERT_EQ(got.scans.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    SCOPED_TRACE(k);
    const Pose2& p = got.scans[static_cast<std::size_t>(k)].pose;
    EXPECT_NEAR(p.x_m, 0.2, 1e-9);
    EXPECT_NEAR(p.y_m, k + 0.5, 1e-9);
    EXPECT_NEAR(p.yaw_rad, M_PI / 2, 1e-9);
  }
  config.pose.name = "nowhere";
  EXPECT_THROW(readRosbag2(dir / "bag.mcap", config, Collector{}.callback()), DataError);
}

/// Writes the fuzz seeds (tests/fuzz/corpus/mcap, cdr) into $LIDARCAL_FUZZ_SEEDS when set:
/// `LIDARCAL_FUZZ_SEEDS=tests/fuzz/corpus build/tests/test_import_rosbag2
/// --gtest_also_run_disabled_tests --gtest_filter='*WriteFuzzSeeds*'`.
TEST(Rosbag2Seeds, DISABLED_WriteFuzzSeeds) {
  const char* root = std::getenv("LIDARCAL_FUZZ_SEEDS");
  if (!root) GTEST_SKIP() << "LIDARCAL_FUZZ_SEEDS not set";
  const fs::path mcap = fs::path(root) / "mcap", cdr = fs::path(root) / "cdr";
  fs::create_directories(mcap);
  fs::create_directories(cdr);
  test::writeFile(mcap / "two_chunks_zstd_lz4.mcap", mcapBag({"zstd", "lz4", false}));
  test::writeFile(mcap / "two_chunks_uncompressed_big_endian.mcap", mcapBag({"", "", true}));
  test::writeFile(mcap / "odometry_zstd.mcap", mcapWithOdometry());
  test::writeFile(mcap / "tf_lz4.mcap", mcapWithTf());
  test::writeFile(cdr / "laser_scan_le.cdr", test::laserScanCdr(scanA(1)));
  test::writeFile(cdr / "laser_scan_be.cdr", test::laserScanCdr(scanB(2), true));
  test::writeFile(cdr / "odometry_le.cdr", test::odometryCdr(5, 7, 1.0, 2.0, 0.5));
  test::writeFile(
      cdr / "tf_be.cdr",
      test::tfMessageCdr({{1, "map", "odom", 1, 2, 3}, {2, "odom", "base", 4, 5, 6}}, true));
}

// ---- SQLite (.db3) and rosbag2 directories ----

std::string metadataYaml(const std::string& storage, const std::vector<std::string>& files) {
  std::string y = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: " + storage +
                  "\n  duration:\n    nanoseconds: 6000000000\n  message_count: 7\n"
                  "  topics_with_message_count:\n    - topic_metadata:\n        name: /scan\n"
                  "        type: sensor_msgs/msg/LaserScan\n        serialization_format: cdr\n"
                  "        offered_qos_profiles: \"\"\n      message_count: 7\n"
                  "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n";
  for (const auto& f : files) y += "    - " + f + "\n";
  y += "  files:\n";
  for (const auto& f : files) y += "    - path: " + f + "\n      message_count: 1\n";
  return y;
}

/// A rosbag2 directory of two .db3 files: scans 0-3 in the first (inserted out of time order),
/// 4-6 in the second; /odom_dummy of another type in the first.
fs::path db3Bag(const TempDir& dir, bool big_endian = false) {
  const fs::path bag = dir / "bag_db3";
  fs::create_directories(bag);
  const std::vector<std::tuple<int, std::string, std::string>> topics = {
      {1, "/scan", "sensor_msgs/msg/LaserScan"}, {2, "/chatter", "std_msgs/msg/String"}};
  std::vector<test::Db3Message> first, second;
  for (int k : {2, 0, 3, 1})
    first.push_back({1, 1000 + 10 * k, test::laserScanCdr(scanA(k), big_endian)});
  first.push_back({2, 1005, "\0\1\0\0\3\0\0\0hi\0"s});
  for (int k = 4; k < 7; ++k)
    second.push_back({1, 1000 + 10 * k, test::laserScanCdr(scanA(k), big_endian)});
  test::writeDb3(bag / "bag_db3_0.db3", topics, first);
  test::writeDb3(bag / "bag_db3_1.db3", topics, second);
  test::writeFile(bag / "metadata.yaml",
                  metadataYaml("sqlite3", {"bag_db3_0.db3", "bag_db3_1.db3"}));
  return bag;
}

TEST(Rosbag2Db3, DirectoryOfTwoFilesGivesTheScansInTimeOrderAndTheTestsPoints) {
  TempDir dir;
  const fs::path bag = db3Bag(dir);
  EXPECT_EQ(detectRecordingFormat(bag).kind, RecordingKind::rosbag2);
  const auto topics = listRosbag2Topics(bag);
  ASSERT_EQ(topics.size(), 2u);
  EXPECT_EQ(topics[1].topic, "/scan");
  EXPECT_EQ(topics[1].messages, 7u);
  importAndExpectPoints(bag.string(), dir / "seq", scanA, 7);
  // One .db3 file on its own (big-endian CDR this time).
  TempDir other;
  const fs::path bag2 = db3Bag(other, true);
  Collector got;
  readRosbag2(bag2 / "bag_db3_1.db3", RosbagConfig{}, got.callback());
  ASSERT_EQ(got.scans.size(), 3u);
  EXPECT_EQ(got.scans[0].ranges_m[0], scanA(4).ranges[0]);
  EXPECT_NEAR(got.scans[2].stamp_s, 106.5, 1e-9);
}

TEST(Rosbag2Directory, McapFilesInTheOrderOfTheMetadata) {
  TempDir dir;
  const fs::path bag = dir / "bag_mcap";
  fs::create_directories(bag);
  using namespace test;
  const std::string defs =
      schemaRecord(1, "sensor_msgs/msg/LaserScan") + channelRecord(1, 1, "/scan");
  std::string a = defs, b = defs;
  for (int k = 0; k < 4; ++k) a += messageRecord(1, 1000 + 10 * k, laserScanCdr(scanA(k)));
  for (int k = 4; k < 7; ++k) b += messageRecord(1, 1000 + 10 * k, laserScanCdr(scanA(k)));
  writeFile(bag / "b_0.mcap", mcapHead() + chunkRecord(a, "zstd", 1000, 1030) + mcapTail());
  writeFile(bag / "b_1.mcap", mcapHead() + chunkRecord(b, "lz4", 1040, 1060) + mcapTail());
  writeFile(bag / "metadata.yaml", metadataYaml("mcap", {"b_0.mcap", "b_1.mcap"}));
  Collector got;
  const ImportReport r = readRosbag2(bag, RosbagConfig{}, got.callback());
  ASSERT_EQ(got.scans.size(), 7u);
  for (int k = 0; k < 7; ++k)
    EXPECT_NEAR(got.scans[static_cast<std::size_t>(k)].stamp_s, 100.5 + k, 1e-9);
  EXPECT_EQ(r.scans, 7u);
}

// ---- CDR ----

TEST(Cdr, AlignmentAfterStringsOfEveryLengthInBothByteOrders) {
  for (bool big : {false, true})
    for (const char* frame : {"", "a", "ab", "abc", "abcd", "abcde"}) {
      SCOPED_TRACE(std::string(frame) + (big ? " big" : " little"));
      TestScan s = scanA(1);
      s.frame_id = frame;
      const std::string bytes = test::laserScanCdr(s, big);
      Ros2LaserScan msg;
      decodeLaserScan(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), msg);
      EXPECT_EQ(msg.frame_id, frame);
      EXPECT_EQ(msg.stamp_sec, 101);
      EXPECT_EQ(msg.stamp_nanosec, 500000000u);
      EXPECT_EQ(msg.range_max, 12.0f);
      ASSERT_EQ(msg.ranges.size(), kBeams);
      EXPECT_EQ(msg.ranges[8], s.ranges[8]);
      EXPECT_EQ(msg.intensities, s.intensities);
    }
}

TEST(Cdr, EveryTruncationAndAHugeCountAreCleanErrors) {
  const std::string bytes = test::laserScanCdr(scanA(2));
  Ros2LaserScan msg;
  for (std::size_t n = 0; n < bytes.size(); ++n)
    EXPECT_THROW(decodeLaserScan(reinterpret_cast<const std::uint8_t*>(bytes.data()), n, msg),
                 InputError)
        << n;
  std::string huge = bytes;
  // the ranges' count: two counts and 2 x 9 floats follow
  const std::size_t count_at = bytes.size() - 4 * (2 * kBeams + 2);
  huge.replace(count_at, 4, "\xff\xff\xff\x7f", 4);
  EXPECT_THROW(
      decodeLaserScan(reinterpret_cast<const std::uint8_t*>(huge.data()), huge.size(), msg),
      InputError);
  const std::string xcdr2 = "\x00\x07\x00\x00"s + bytes.substr(4);
  EXPECT_THROW(
      decodeLaserScan(reinterpret_cast<const std::uint8_t*>(xcdr2.data()), xcdr2.size(), msg),
      InputError);
}

// ---- corrupt input: a clean error naming the file and what is wrong, exit 2, nothing written ----

void expectCliError(const TempDir& dir, const fs::path& input,
                    const std::vector<std::string>& parts,
                    const std::string& from = "--from rosbag2 ") {
  const auto r =
      test::runCli("import -q " + from + input.string() + " -o " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  for (const auto& p : parts)
    EXPECT_NE(r.err.find(p), std::string::npos) << r.err << "\nmissing: " << p;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

/// Replaces the 8-byte little-endian field at `at` with `value`.
std::string patch64(std::string bytes, std::size_t at, std::uint64_t value) {
  bytes.replace(at, 8, test::le(value, 8));
  return bytes;
}

TEST(Rosbag2BadInput, CorruptMcapFilesGiveCleanErrors) {
  TempDir dir;
  using namespace test;
  const std::string good = mcapBag({"zstd", "lz4", false});
  const std::size_t chunk_at = mcapHead().size();  // the first Chunk record
  const std::string records = schemaRecord(1, "sensor_msgs/msg/LaserScan") +
                              channelRecord(1, 1, "/scan") +
                              messageRecord(1, 5, laserScanCdr(scanA(0)));
  const auto write = [&](const std::string& name, const std::string& bytes) {
    writeFile(dir / name, bytes);
    return dir / name;
  };
  expectCliError(dir, write("cut.mcap", good.substr(0, good.size() / 2)),
                 {"cut.mcap", "(Chunk)", "cut short", "mcap recover"});
  expectCliError(dir, write("cut2.mcap", good.substr(0, chunk_at)),
                 {"cut2.mcap", "without a Footer", "mcap recover"});
  expectCliError(dir, write("magic.mcap", "\x89MCAP1\r\n"s + good.substr(8)),
                 {"magic.mcap", "magic"});
  expectCliError(dir, write("long.mcap", patch64(good, chunk_at + 1, 1u << 30)),
                 {"long.mcap", "(Chunk)", "past the end"});
  // uncompressed_size (after start and end times) one byte off, for each compression.
  for (const char* c : {"", "zstd", "lz4"}) {
    SCOPED_TRACE(c);
    const std::string bag = mcapHead() + chunkRecord(records, c, 5, 5) + mcapTail();
    expectCliError(dir, write("size.mcap", patch64(bag, chunk_at + 9 + 16, records.size() + 1)),
                   {"size.mcap", "uncompressed"});
    expectCliError(dir, write("size2.mcap", patch64(bag, chunk_at + 9 + 16, records.size() - 1)),
                   {"size2.mcap", "Chunk"});
  }
  expectCliError(dir,
                 write("bz2.mcap", mcapHead() + chunkRecord(records, "bz2", 5, 5) + mcapTail()),
                 {"bz2.mcap", "unknown compression 'bz2'"});
  expectCliError(
      dir,
      write("crc.mcap", mcapHead() +
                            record(0x06, chunkRecord(records, "", 5, 5).substr(9, 28) + mstr("") +
                                             le(records.size(), 8) +
                                             records.substr(0, records.size() - 1) + "X") +
                            mcapTail()),
      {"crc.mcap", "CRC"});
  expectCliError(dir, write("nochannel.mcap", mcapHead() + messageRecord(7, 5, "x") + mcapTail()),
                 {"channel 7"});
}

TEST(Rosbag2BadInput, EveryTruncationAndRandomByteChangesAreResultsOrInputErrors) {
  const std::string good = mcapBag({"zstd", "lz4", true});
  TempDir dir;
  const fs::path file = dir / "f.mcap";
  auto attempt = [&](const std::string& bytes) {
    test::writeFile(file, bytes);
    try {
      readRosbag2(file, RosbagConfig{"/scan", {}, {}, {}, {}},
                  [](const RawScan& s) { return s.angles_rad.size() == s.ranges_m.size(); });
    } catch (const InputError&) {
    }
  };
  for (std::size_t n = 0; n < good.size(); n += 7) EXPECT_NO_THROW(attempt(good.substr(0, n))) << n;
  std::mt19937 rng(21);
  for (int trial = 0; trial < 400; ++trial) {
    std::string bytes = good;
    const std::size_t at = std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(rng);
    bytes[at] = static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
    EXPECT_NO_THROW(attempt(bytes)) << "byte " << at;
  }
}

TEST(Rosbag2BadInput, DirectoriesWithBadMetadataAndBadDb3Files) {
  TempDir dir;
  const fs::path bag = db3Bag(dir);
  test::writeFile(bag / "metadata.yaml",
                  metadataYaml("sqlite3", {"bag_db3_0.db3", "bag_db3_9.db3"}));
  expectCliError(dir, bag,
                 {"metadata.yaml", "relative_file_paths", "bag_db3_9.db3", "ros2 bag reindex"}, "");
  test::writeFile(bag / "metadata.yaml",
                  "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n");
  expectCliError(dir, bag, {"metadata.yaml", "relative_file_paths", "missing"});
  test::writeFile(bag / "metadata.yaml", metadataYaml("rosbag_v2", {"bag_db3_0.db3"}));
  expectCliError(dir, bag, {"storage_identifier", "rosbag_v2"});
  fs::remove(bag / "metadata.yaml");
  expectCliError(dir, bag, {"metadata.yaml", "missing"});
  // A .db3 without the rosbag2 tables, and a file that is no database.
  test::writeDb3(dir / "empty.db3", {}, {});
  sqlite3* db = nullptr;
  sqlite3_open((dir / "other.db3").c_str(), &db);
  sqlite3_exec(db, "CREATE TABLE t(x);", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  expectCliError(dir, dir / "other.db3", {"other.db3", "table topics", "no such table"});
  expectCliError(dir, dir / "empty.db3", {"empty.db3", "holds no sensor_msgs/msg/LaserScan topic"});
  test::writeFile(dir / "notes.txt", "hello\n");
  expectCliError(dir, dir / "notes.txt", {"notes.txt", "neither an MCAP file nor"});
  // A message whose CDR is cut short.
  test::writeDb3(dir / "short.db3", {{1, "/scan", "sensor_msgs/msg/LaserScan"}},
                 {{1, 5, test::laserScanCdr(scanA(0)).substr(0, 30)}});
  expectCliError(dir, dir / "short.db3",
                 {"short.db3", "topic /scan, message 0", "not a valid CDR"});
}

}  // namespace
}  // namespace lidarcal::io
