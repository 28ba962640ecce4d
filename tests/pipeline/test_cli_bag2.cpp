// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal correct` on ROS 2 bags (.mcap, .db3, rosbag2 directories) through the binary: the
// corrected bag re-imports to the ranges `correct` gives on the imported sequence, every other
// message and every stamp is kept byte for byte, the MCAP written is valid (read back by
// lidarcal's reader, record by record), ROS1 <-> ROS 2 names are refused with the remedy, and a
// rig model corrects each LaserScan topic with its own block in one pass.

#include <cmath>
#include <limits>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "io/bag_scans.hpp"
#include "io/import_rosbag2.hpp"
#include "io/mcap_reader.hpp"
#include "io/pcd_scan.hpp"
#include "io/rig.hpp"
#include "io/ros2_msgs.hpp"
#include "io/rosbag2_test_writer.hpp"
#include "io/sequence.hpp"
#include "pipeline/ros_test_util.hpp"

namespace lidarcal::test {
namespace {

constexpr std::size_t kBeams = 100;

/// Equal floats, NaN equal to NaN.
bool sameFloat(float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

TestScan scan(int k) { return recordedScan(k, kBeams); }

/// A std_msgs/msg/String message in CDR ("other topic" traffic that must pass untouched).
std::string stringCdr(const std::string& text) {
  CdrWriter w(false);
  w.str(text);
  return w.bytes();
}

/// 30 scans on /scan (zstd chunks of 10 messages) with a /chatter message after each, big- and
/// little-endian scans mixed.
void writeMcap(const fs::path& file) {
  std::string out = mcapHead() + schemaRecord(1, "sensor_msgs/msg/LaserScan") +
                    schemaRecord(2, "std_msgs/msg/String") + channelRecord(1, 1, "/scan") +
                    channelRecord(2, 2, "/chatter");
  std::string chunk;
  for (int k = 0; k < 30; ++k) {
    const std::uint64_t t = 1000000000ull * static_cast<std::uint64_t>(100 + k);
    chunk += messageRecord(1, t, laserScanCdr(scan(k), k % 3 == 0));
    chunk += messageRecord(2, t + 5, stringCdr("hello " + std::to_string(k)));
    if (k % 10 == 9) {
      out += chunkRecord(chunk, "zstd", t - 9000000000ull, t + 5);
      chunk.clear();
    }
  }
  writeFile(file, out + mcapTail());
}

/// Every message of an MCAP: topic, log time, bytes (in the reader's order).
struct Recorded {
  std::string topic;
  std::uint64_t log_time, publish_time;
  std::uint32_t sequence;
  std::vector<std::uint8_t> bytes;
};
std::vector<Recorded> messagesOf(const fs::path& file) {
  const io::McapReader r(file);
  std::set<std::string> topics;
  for (const auto& c : r.channels()) topics.insert(c.topic);
  std::vector<Recorded> out;
  r.forEachMessage(topics, [&](const io::McapMessage& m) {
    out.push_back({m.channel->topic,
                   m.log_time_ns,
                   m.publish_time_ns,
                   m.sequence,
                   {m.data, m.data + m.size}});
    return true;
  });
  return out;
}

/// The ranges of the bag's LaserScan `topic` (empty: its only one) as the importer reads them.
std::vector<std::vector<float>> importedRanges(const fs::path& bag, const std::string& topic = "") {
  std::vector<std::vector<float>> out;
  io::RosbagConfig config;
  config.topic = topic;
  io::readRosbag2(bag, config, [&](const io::RawScan& s) {
    out.push_back(s.ranges_m);
    return true;
  });
  return out;
}

class CorrectRosbag2 : public ::testing::Test {
 protected:
  void SetUp() override {
    writeMcap(dir / "in.mcap");
    io::writeModel(dir / "model.json", polynomialModel("", static_cast<int>(kBeams)));
  }
  CliResult correct(const std::string& in, const std::string& out, const std::string& extra = "") {
    return runCli("correct " + (dir / in).string() + " --model " + (dir / "model.json").string() +
                  " -o " + (dir / out).string() + " " + extra);
  }
  TempDir dir;
};

TEST_F(CorrectRosbag2, McapReimportsToTheRangesCorrectGivesOnTheImportedSequence) {
  ASSERT_EQ(correct("in.mcap", "out.mcap").exit_code, 0);
  // `correct` on the imported sequence: the truth for the corrected ranges.
  ASSERT_EQ(
      runCli("import " + (dir / "in.mcap").string() + " -o " + (dir / "seq").string()).exit_code,
      0);
  ASSERT_EQ(correct("seq", "seq-corrected").exit_code, 0);
  const io::Sequence seq = io::openSequence(dir / "seq-corrected");
  const auto bag = importedRanges(dir / "out.mcap"), raw = importedRanges(dir / "in.mcap");
  ASSERT_EQ(bag.size(), 30u);
  ASSERT_EQ(seq.scans.size(), bag.size());
  std::size_t changed = 0;
  for (std::size_t k = 0; k < bag.size(); ++k) {
    SCOPED_TRACE(k);
    const io::Scan s = io::readScan(seq.scans.path(k));
    ASSERT_EQ(s.cloud->size(), bag[k].size());
    for (std::size_t i = 0; i < bag[k].size(); ++i) {
      const auto& p = (*s.cloud)[i];
      const float r = bag[k][i];
      // not a return in the sequence: the bag keeps the raw value
      if (!std::isfinite(p.x)) continue;
      // points are floats: the range to their precision
      EXPECT_NEAR(std::hypot(p.x, p.y), r, 2e-6 * r) << i;
      changed += r != raw[k][i];
    }
  }
  EXPECT_GT(changed, 30u * 50u);  // most readings lie in the fitted range and moved
}

TEST_F(CorrectRosbag2, McapKeepsEveryOtherMessageAndStampByteForByte) {
  ASSERT_EQ(correct("in.mcap", "out.mcap").exit_code, 0);
  const auto in = messagesOf(dir / "in.mcap"), out = messagesOf(dir / "out.mcap");
  ASSERT_EQ(in.size(), 60u);
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t j = 0; j < in.size(); ++j) {
    SCOPED_TRACE(j);
    EXPECT_EQ(out[j].topic, in[j].topic);
    EXPECT_EQ(out[j].log_time, in[j].log_time);
    EXPECT_EQ(out[j].publish_time, in[j].publish_time);
    EXPECT_EQ(out[j].sequence, in[j].sequence);
    ASSERT_EQ(out[j].bytes.size(), in[j].bytes.size());
    if (in[j].topic != "/scan") {
      EXPECT_EQ(out[j].bytes, in[j].bytes);
      continue;
    }
    // A scan differs only inside its ranges.
    io::Ros2LaserScan a, b;
    io::decodeLaserScan(in[j].bytes.data(), in[j].bytes.size(), a);
    io::decodeLaserScan(out[j].bytes.data(), out[j].bytes.size(), b);
    for (std::size_t at = 0; at < in[j].bytes.size(); ++at) {
      if (at < a.ranges_offset || at >= a.ranges_offset + 4 * a.ranges.size()) {
        EXPECT_EQ(out[j].bytes[at], in[j].bytes[at]) << at;
      }
    }
    EXPECT_EQ(b.frame_id, a.frame_id);
    EXPECT_EQ(b.intensities, a.intensities);
  }
  const io::McapReader reader(dir / "out.mcap");  // schemas and channels as recorded
  ASSERT_EQ(reader.channels().size(), 2u);
  EXPECT_EQ(reader.channels()[0].schema_name, "sensor_msgs/msg/LaserScan");
  EXPECT_EQ(reader.channels()[0].schema_encoding, "ros2msg");
  EXPECT_EQ(reader.channels()[1].message_encoding, "cdr");
}

TEST_F(CorrectRosbag2, Db3AndDirectoriesGiveTheSameRangesAsMcap) {
  ASSERT_EQ(correct("in.mcap", "out.mcap").exit_code, 0);
  const auto expected = importedRanges(dir / "out.mcap");
  std::vector<Db3Message> rows;
  for (int k = 0; k < 30; ++k) {
    rows.push_back({1, 1000000000ll * (100 + k), laserScanCdr(scan(k), k % 3 == 0)});
    rows.push_back({2, 1000000000ll * (100 + k) + 5, stringCdr("hello")});
  }
  fs::create_directories(dir / "bag");
  writeDb3(dir / "bag" / "bag_0.db3",
           {{1, "/scan", "sensor_msgs/msg/LaserScan"}, {2, "/chatter", "std_msgs/msg/String"}},
           rows);
  const std::string yaml =
      "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  "
      "relative_file_paths:\n    - bag_0.db3\n";
  writeFile(dir / "bag" / "metadata.yaml", yaml);
  ASSERT_EQ(correct("bag/bag_0.db3", "out.db3").exit_code, 0);
  ASSERT_EQ(correct("bag", "out-bag").exit_code, 0);
  EXPECT_EQ(readFile(dir / "out-bag" / "metadata.yaml"), yaml);
  for (const fs::path& bag : {dir / "out.db3", dir / "out-bag"}) {
    SCOPED_TRACE(bag.string());
    const auto got = importedRanges(bag);
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t k = 0; k < got.size(); ++k)
      for (std::size_t i = 0; i < got[k].size(); ++i)
        EXPECT_TRUE(sameFloat(got[k][i], expected[k][i])) << k << " " << i;
  }
}

TEST_F(CorrectRosbag2, RefusesToTurnOneKindOfBagIntoAnotherNamingTheRemedy) {
  writeFile(dir / "in.bag", "#ROSBAG V2.0\n");  // recognised as a ROS1 bag by its first line
  const CliResult ros1 = correct("in.bag", "out.mcap");
  EXPECT_EQ(ros1.exit_code, 2);
  EXPECT_NE(ros1.err.find("-o OUT.bag"), std::string::npos) << ros1.err;
  const CliResult ros2 = correct("in.mcap", "out.bag");
  EXPECT_EQ(ros2.exit_code, 2);
  EXPECT_NE(ros2.err.find("-o OUT.mcap"), std::string::npos) << ros2.err;
  EXPECT_EQ(correct("in.mcap", "out.db3").exit_code, 2);
  EXPECT_FALSE(fs::exists(dir / "out.bag"));
  EXPECT_FALSE(fs::exists(dir / "out.db3"));
}

TEST_F(CorrectRosbag2, AMissingBagFileIsNamedAsAFileNotASequence) {
  for (const char* name : {"missing.mcap", "missing.db3", "missing.bag"}) {
    const CliResult r = correct(name, "out.mcap");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find(std::string(name) + ": file does not exist (check the path)"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find("sequence"), std::string::npos) << r.err;
  }
}

/// Scans on /scan and /scan_b (the back lidar's readings 0.3 m longer) and /chatter after each, at
/// time k; the rows of the same bag as .db3 into `rows`.
void writeTwoLidarMcap(const fs::path& file, std::vector<Db3Message>& rows) {
  std::string out = mcapHead() + schemaRecord(1, "sensor_msgs/msg/LaserScan") +
                    schemaRecord(2, "std_msgs/msg/String") + channelRecord(1, 1, "/scan") +
                    channelRecord(2, 2, "/chatter") + channelRecord(3, 1, "/scan_b");
  std::string chunk;
  for (int k = 0; k < 8; ++k) {
    const std::uint64_t t = 1000000000ull * static_cast<std::uint64_t>(100 + k);
    TestScan back = scan(k);
    back.frame_id = "laser_back";
    for (float& r : back.ranges) r += 0.3f;
    const std::string messages[] = {laserScanCdr(scan(k), k % 3 == 0),
                                    laserScanCdr(back, k % 2 == 0),
                                    stringCdr("hi " + std::to_string(k))};
    for (const int c : {0, 1, 2}) {
      const int channel = c == 0 ? 1 : c == 1 ? 3 : 2;
      chunk += messageRecord(static_cast<std::uint16_t>(channel), t + static_cast<std::uint64_t>(c),
                             messages[c]);
      rows.push_back({channel, static_cast<std::int64_t>(t) + c, messages[c]});
    }
  }
  writeFile(file, out + chunkRecord(chunk, "zstd", 100000000000ull, 107000000002ull) + mcapTail());
}

/// The bytes of every message on `topic`, in order.
std::vector<std::vector<std::uint8_t>> bytesOn(const std::vector<Recorded>& messages,
                                               const std::string& topic) {
  std::vector<std::vector<std::uint8_t>> out;
  for (const Recorded& m : messages)
    if (m.topic == topic) out.push_back(m.bytes);
  return out;
}

TEST_F(CorrectRosbag2, RigModelCorrectsEachTopicWithItsOwnBlockInOnePass) {
  std::vector<Db3Message> rows;
  writeTwoLidarMcap(dir / "two.mcap", rows);
  const io::RigModel rig = twoLidarModel("/scan", "/scan_b");
  io::writeRigModel(dir / "rig.json", rig);
  const std::string model = " --model " + (dir / "rig.json").string();
  const CliResult r = runCli("correct " + (dir / "two.mcap").string() + model + " -o " +
                             (dir / "rig.mcap").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The truth: each topic alone corrected with its block as a single-sensor model.
  for (const std::size_t b : {0, 1}) {
    io::writeModel(dir / (rig.sensors[b].name + ".json"), rig.sensors[b].model);
    const CliResult one =
        runCli("correct " + (dir / "two.mcap").string() + " --model " +
               (dir / (rig.sensors[b].name + ".json")).string() + " --topic " +
               rig.sensors[b].topic + " -o " + (dir / (rig.sensors[b].name + ".mcap")).string());
    ASSERT_EQ(one.exit_code, 0) << one.err;
  }
  const auto in = messagesOf(dir / "two.mcap"), out = messagesOf(dir / "rig.mcap");
  ASSERT_EQ(in.size(), 24u);
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t j = 0; j < in.size(); ++j) {
    EXPECT_EQ(out[j].topic, in[j].topic) << j;
    EXPECT_EQ(out[j].log_time, in[j].log_time) << j;
    EXPECT_EQ(out[j].publish_time, in[j].publish_time) << j;
    EXPECT_EQ(out[j].sequence, in[j].sequence) << j;
    if (in[j].topic == "/chatter")
      EXPECT_EQ(out[j].bytes, in[j].bytes) << j;
    else
      EXPECT_NE(out[j].bytes, in[j].bytes) << j;  // its ranges moved
  }
  // Bit for bit the single-topic runs' messages: the same ranges, every other byte the input's.
  EXPECT_EQ(bytesOn(out, "/scan"), bytesOn(messagesOf(dir / "front.mcap"), "/scan"));
  EXPECT_EQ(bytesOn(out, "/scan_b"), bytesOn(messagesOf(dir / "back.mcap"), "/scan_b"));
  // The other block would have given other ranges: each topic did get its own.
  ASSERT_EQ(
      runCli("correct " + (dir / "two.mcap").string() + " --model " +
             (dir / "front.json").string() + " --topic /scan_b -o " + (dir / "wrong.mcap").string())
          .exit_code,
      0);
  EXPECT_NE(bytesOn(out, "/scan_b"), bytesOn(messagesOf(dir / "wrong.mcap"), "/scan_b"));
  // --sensor narrows to one block: the other topic is copied as it was.
  const CliResult back = runCli("correct " + (dir / "two.mcap").string() + model +
                                " --sensor back -o " + (dir / "only-back.mcap").string());
  ASSERT_EQ(back.exit_code, 0) << back.err;
  const auto narrowed = messagesOf(dir / "only-back.mcap");
  EXPECT_EQ(bytesOn(narrowed, "/scan"), bytesOn(in, "/scan"));
  EXPECT_EQ(bytesOn(narrowed, "/scan_b"), bytesOn(out, "/scan_b"));
  // A .db3 of the same messages, alone and in a rosbag2 directory: the same ranges.
  writeDb3(dir / "two.db3",
           {{1, "/scan", "sensor_msgs/msg/LaserScan"},
            {2, "/chatter", "std_msgs/msg/String"},
            {3, "/scan_b", "sensor_msgs/msg/LaserScan"}},
           rows);
  fs::create_directories(dir / "bag");
  fs::copy_file(dir / "two.db3", dir / "bag" / "bag_0.db3");
  writeFile(dir / "bag" / "metadata.yaml",
            "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
            "  relative_file_paths:\n    - bag_0.db3\n");
  ASSERT_EQ(
      runCli("correct " + (dir / "two.db3").string() + model + " -o " + (dir / "rig.db3").string())
          .exit_code,
      0);
  ASSERT_EQ(
      runCli("correct " + (dir / "bag").string() + model + " -o " + (dir / "rig-bag").string())
          .exit_code,
      0);
  for (const std::string bag : {"rig.db3", "rig-bag"})
    for (const std::string topic : {"/scan", "/scan_b"}) {
      SCOPED_TRACE(bag + " " + topic);
      const auto got = importedRanges(dir / bag, topic),
                 mcap = importedRanges(dir / "rig.mcap", topic);
      ASSERT_EQ(got.size(), 8u);
      ASSERT_EQ(got.size(), mcap.size());
      for (std::size_t k = 0; k < got.size(); ++k)
        for (std::size_t i = 0; i < got[k].size(); ++i)
          EXPECT_TRUE(sameFloat(got[k][i], mcap[k][i])) << k << " " << i;
    }
}

TEST(ImportRigRosbag2, TwoLidarTopicsOfAnMcapImportAsARigWithEachScanUnderItsSensor) {
  TempDir dir;
  std::vector<Db3Message> rows;
  writeTwoLidarMcap(dir / "two.mcap", rows);
  // Without /tf_static nothing says which frame the two lidars share: import asks for it by name.
  const std::string args =
      " --topic /scan,/scan_b --sensor-names front,back -o " + (dir / "rig").string();
  const CliResult unnamed = runCli("import " + (dir / "two.mcap").string() + args);
  EXPECT_EQ(unnamed.exit_code, 2);
  EXPECT_NE(unnamed.err.find("--vehicle-frame"), std::string::npos) << unnamed.err;
  EXPECT_FALSE(fs::exists(dir / "rig"));
  const CliResult r =
      runCli("import " + (dir / "two.mcap").string() + args + " --vehicle-frame base_link");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const io::Rig rig = io::openRig(dir / "rig");
  ASSERT_EQ(rig.meta.sensors.size(), 2u);
  EXPECT_EQ(rig.meta.sensors[0].topic, "/scan");
  EXPECT_EQ(rig.meta.sensors[1].topic, "/scan_b");
  EXPECT_EQ(rig.meta.sensors[1].frame_id, "laser_back");
  ASSERT_EQ(rig.scans.size(), 16u);
  // Each sensor's sequence holds its own topic's ranges, scan by scan, as a single-topic import
  // reads them.
  for (const std::size_t s : {0, 1}) {
    SCOPED_TRACE(rig.meta.sensors[s].name);
    const auto want = importedRanges(dir / "two.mcap", rig.meta.sensors[s].topic);
    ASSERT_EQ(rig.sequences[s].scans.size(), want.size());
    for (std::size_t k = 0; k < want.size(); ++k) {
      const io::Scan scan = io::readScan(rig.sequences[s].scans[k].path);
      ASSERT_EQ(scan.cloud->size(), want[k].size());
      std::size_t returns = 0;  // readings outside the scan's range window import as no return
      for (std::size_t i = 0; i < want[k].size(); ++i) {
        const auto& p = (*scan.cloud)[i];
        if (!std::isfinite(p.x)) continue;
        ++returns;
        EXPECT_NEAR(std::hypot(p.x, p.y), want[k][i], 1e-5) << k << " " << i;
      }
      EXPECT_GT(returns, want[k].size() / 2) << k;
    }
  }
}

TEST_F(CorrectRosbag2, AModelOfAnotherSensorWritesNothing) {
  io::writeModel(dir / "model.json", polynomialModel("", 360));
  const CliResult r = correct("in.mcap", "out.mcap");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out.mcap"));
}

}  // namespace
}  // namespace lidarcal::test
