// SPDX-License-Identifier: BSD-3-Clause
// lidarcal_ros2_node (Cyclone DDS) against a ROS 2 peer on the other vendor's DDS (Fast DDS, in
// this process), both on loopback only and on a domain of this run's own: recorded scans published
// under ROS 2's names and QoS, the corrected scans received and compared bit for bit with
// `lidarcal correct IN.mcap -o OUT.mcap`; a model of another sensor refused, malformed scans
// dropped while the node runs on, a publisher that goes away and comes back. Every wait is
// bounded (discovery and delivery are waited for, never slept through); processes are ended by pid.

#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <set>

#include <gtest/gtest.h>

#include "child_process.hpp"
#include "io/mcap_reader.hpp"
#include "io/model_yaml.hpp"
#include "io/ros2_msgs.hpp"
#include "io/rosbag2_test_writer.hpp"
#include "pipeline/ros_test_util.hpp"
#include "ros2/fastdds_peer.hpp"

namespace lidarcal::test {
namespace {

constexpr std::size_t kBeams = 100;
constexpr double kDiscoveryS = 30.0, kDeliveryS = 10.0;

bool sameFloat(float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

/// A decoded LaserScan as the Fast DDS type.
Ros2Scan toDds(const io::Ros2LaserScan& m) {
  Ros2Scan s;
  s.header().stamp().sec(m.stamp_sec);
  s.header().stamp().nanosec(m.stamp_nanosec);
  s.header().frame_id(m.frame_id);
  s.angle_min(m.angle_min);
  s.angle_max(m.angle_max);
  s.angle_increment(m.angle_increment);
  s.time_increment(m.time_increment);
  s.scan_time(m.scan_time);
  s.range_min(m.range_min);
  s.range_max(m.range_max);
  s.ranges(m.ranges);
  s.intensities(m.intensities);
  return s;
}

/// The LaserScans of an MCAP's /scan, decoded.
std::vector<io::Ros2LaserScan> scansOf(const fs::path& mcap) {
  std::vector<io::Ros2LaserScan> out;
  io::McapReader(mcap).forEachMessage({"/scan"}, [&](const io::McapMessage& m) {
    out.emplace_back();
    io::decodeLaserScan(m.data, m.size, out.back());
    return true;
  });
  return out;
}

/// Everything but the ranges' values is the sent scan's; the ranges are `expected`, bit for bit.
void expectCorrected(const Ros2Scan& got, const io::Ros2LaserScan& sent,
                     const std::vector<float>& expected) {
  EXPECT_EQ(got.header().stamp().sec(), sent.stamp_sec);
  EXPECT_EQ(got.header().stamp().nanosec(), sent.stamp_nanosec);
  EXPECT_EQ(got.header().frame_id(), sent.frame_id);
  EXPECT_EQ(got.angle_min(), sent.angle_min);
  EXPECT_EQ(got.angle_max(), sent.angle_max);
  EXPECT_EQ(got.angle_increment(), sent.angle_increment);
  EXPECT_EQ(got.time_increment(), sent.time_increment);
  EXPECT_EQ(got.scan_time(), sent.scan_time);
  EXPECT_EQ(got.range_min(), sent.range_min);
  EXPECT_EQ(got.range_max(), sent.range_max);
  EXPECT_EQ(got.intensities(), sent.intensities);
  ASSERT_EQ(got.ranges().size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_TRUE(sameFloat(got.ranges()[i], expected[i]))
        << i << ": " << got.ranges()[i] << " vs " << expected[i];
}

class Ros2Node : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // This run's own domain, loopback only, for the node (Cyclone: CYCLONEDDS_URI) and the peer.
    domain_ = uniqueDomainId();
    setenv("ROS_DOMAIN_ID", std::to_string(domain_).c_str(), 1);
    setenv("CYCLONEDDS_URI", cycloneLoopbackConfig().c_str(), 1);
  }

  void SetUp() override {
    writeFile(dir / "in.mcap", recording());
    io::writeModel(dir / "model.json", polynomialModel("", static_cast<int>(kBeams)));
    peer = std::make_unique<FastDdsPeer>(domain_);
  }

  /// 30 scans on /scan in one zstd chunk.
  static std::string recording() {
    std::string records;
    for (int k = 0; k < 30; ++k)
      records += messageRecord(1, 1000000000ull * static_cast<std::uint64_t>(100 + k),
                               laserScanCdr(recordedScan(k, kBeams)));
    return mcapHead() + schemaRecord(1, "sensor_msgs/msg/LaserScan") +
           channelRecord(1, 1, "/scan") +
           chunkRecord(records, "zstd", 100000000000ull, 129000000000ull) + mcapTail();
  }

  Child startNode(const std::string& name, const std::vector<std::string>& params) {
    std::vector<std::string> argv = {LIDARCAL_ROS2_NODE_EXE, "--ros-args", "-r", "__node:=" + name};
    for (const auto& p : params) {
      argv.push_back("-p");
      argv.push_back(p);
    }
    return Child(argv, dir / (name + ".log"));
  }

  /// Publishes `scan` until its corrected counterpart comes back (matching is seen by each side
  /// in its own time: a scan sent before the node's reader has matched the writer may be lost).
  void prime(const io::Ros2LaserScan& scan, const Child& node) {
    const std::size_t before = peer->received().size();
    for (int attempt = 0; attempt < 30; ++attempt) {
      peer->publish(toDds(scan));
      ++well_formed_sent_;
      if (peer->waitReceived(before + 1, 1.0)) return;
    }
    FAIL() << "no corrected scan came back: " << node.log();
  }

  /// Publishes each scan and waits for its corrected counterpart before the next.
  void publishAll(const std::vector<io::Ros2LaserScan>& scans, const Child& node) {
    for (std::size_t k = 0; k < scans.size(); ++k) {
      const std::size_t before = peer->received().size();
      peer->publish(toDds(scans[k]));
      ++well_formed_sent_;
      ASSERT_TRUE(peer->waitReceived(before + 1, kDeliveryS))
          << "no corrected scan " << k << ": " << node.log();
    }
  }

  /// Runs `node` (started with reliable input QoS) on `sent` from `input` to `output` and checks
  /// that every scan came back once, known by its stamp, with the ranges of `expected`.
  void expectCorrectedLive(Child& node, const std::string& input, const std::string& output,
                           const std::vector<io::Ros2LaserScan>& sent,
                           const std::vector<io::Ros2LaserScan>& expected) {
    peer = std::make_unique<FastDdsPeer>(domain_);
    well_formed_sent_ = 0;
    peer->subscribe("rt/" + output, PeerQos::reliable);
    peer->advertise("rt/" + input, PeerQos::reliable);
    ASSERT_TRUE(peer->waitMatched(kDiscoveryS))
        << "the node and the peer did not match: " << node.log();
    prime(sent[0], node);
    publishAll(sent, node);
    EXPECT_EQ(node.stop(), 0) << node.log();
    expectSummaryCounts(node);
    // Each received scan is one sent (scan 0 possibly more than once: prime), known by its stamp.
    std::set<std::int32_t> seen;
    for (const Ros2Scan& got : peer->received()) {
      const auto k = static_cast<std::size_t>(got.header().stamp().sec() - sent[0].stamp_sec);
      ASSERT_LT(k, sent.size());
      SCOPED_TRACE(k);
      expectCorrected(got, sent[k], expected[k].ranges);
      seen.insert(got.header().stamp().sec());
    }
    EXPECT_EQ(seen.size(), sent.size());
  }

  /// The node's summary counts every scan the peer received, and no more than it was sent well
  /// formed: a corrected scan published before the node's writer matched the peer's reader (a
  /// race under load) is counted by the node and lost on the wire.
  void expectSummaryCounts(const Child& node) {
    const std::string log = node.log();
    std::smatch m;
    ASSERT_TRUE(std::regex_search(log, m, std::regex("lidarcal_ros2_node: ([0-9]+) scans"))) << log;
    const std::size_t published = std::stoul(m[1].str());
    EXPECT_GE(published, peer->received().size()) << log;
    EXPECT_LE(published, well_formed_sent_) << log;
  }

  static int domain_;
  TempDir dir;
  std::unique_ptr<FastDdsPeer> peer;
  std::size_t well_formed_sent_ = 0;
};
int Ros2Node::domain_ = 0;

TEST_F(Ros2Node, PublishesWhatCorrectWritesToAnMcapBitForBit) {
  // The JSON model with LS, and the same model exported as YAML with ML (the node takes the
  // inversion from the YAML), each against `correct` with that inversion.
  ASSERT_EQ(runCli("export " + (dir / "model.json").string() + " --format yaml --inversion ml -o " +
                   (dir / "model.yaml").string())
                .exit_code,
            0);
  const std::vector<io::Ros2LaserScan> sent = scansOf(dir / "in.mcap");
  ASSERT_EQ(sent.size(), 30u);
  for (const std::string inversion : {"ls", "ml"}) {
    SCOPED_TRACE(inversion);
    const fs::path out = dir / ("out-" + inversion + ".mcap");
    const CliResult c =
        runCli("correct " + (dir / "in.mcap").string() + " --model " +
               (dir / "model.json").string() + " --inversion " + inversion + " -o " + out.string());
    ASSERT_EQ(c.exit_code, 0) << c.err;
    const std::vector<io::Ros2LaserScan> expected = scansOf(out);
    ASSERT_EQ(expected.size(), sent.size());

    const std::string model =
        inversion == "ls" ? (dir / "model.json").string() : (dir / "model.yaml").string();
    Child node = startNode("lidarcal_" + inversion,
                           {"model:=" + model, "input:=raw_" + inversion,
                            "output:=corrected_" + inversion, "input_qos:=default"});
    expectCorrectedLive(node, "raw_" + inversion, "corrected_" + inversion, sent, expected);
    std::size_t changed = 0;
    for (std::size_t k = 0; k < sent.size(); ++k)
      for (std::size_t i = 0; i < kBeams; ++i)
        changed += !sameFloat(expected[k].ranges[i], sent[k].ranges[i]);
    EXPECT_GT(changed, sent.size() * 50);  // most readings lie in the fitted range and moved
  }
}

TEST_F(Ros2Node, PicksTheBlockOfARigModelByTopicOrSensorName) {
  // "back" on /scan (the node's default input), "front" on another topic; `correct` with each
  // block as a single-sensor model is the oracle (a rig model corrects only a block's own topic).
  const fs::path rig = dir / "rig.json";
  const io::RigModel rig_model = twoLidarModel("/scan_front", "/scan");
  io::writeRigModel(rig, rig_model);
  const std::vector<io::Ros2LaserScan> sent = scansOf(dir / "in.mcap");
  std::map<std::string, std::vector<io::Ros2LaserScan>> expected;
  for (const io::RigModelSensor& s : rig_model.sensors) {
    const std::string block = s.name;
    const fs::path out = dir / (block + ".mcap"), model = dir / (block + ".json");
    io::writeModel(model, s.model);
    const CliResult c = runCli("correct " + (dir / "in.mcap").string() + " --model " +
                               model.string() + " -o " + out.string());
    ASSERT_EQ(c.exit_code, 0) << c.err;
    expected[block] = scansOf(out);
    ASSERT_EQ(expected[block].size(), sent.size());
  }
  // the blocks tell apart
  ASSERT_FALSE(sameFloat(expected["front"][0].ranges[50], expected["back"][0].ranges[50]));
  {
    SCOPED_TRACE("by topic");
    Child node = startNode("lidarcal_rig_topic", {"model:=" + rig.string(), "input_qos:=default"});
    expectCorrectedLive(node, "scan", "scan_corrected", sent, expected["back"]);
    EXPECT_NE(node.log().find("block back"), std::string::npos) << node.log();
  }
  {
    SCOPED_TRACE("by sensor_name");
    Child node = startNode("lidarcal_rig_name",
                           {"model:=" + rig.string(), "sensor_name:=front", "input:=raw_rig",
                            "output:=corrected_rig", "input_qos:=default"});
    expectCorrectedLive(node, "raw_rig", "corrected_rig", sent, expected["front"]);
    EXPECT_NE(node.log().find("block front"), std::string::npos) << node.log();
  }
  // No block for the topic or the name: refused at start, the blocks listed.
  for (const std::string p : {"input:=scan_side", "sensor_name:=side"}) {
    SCOPED_TRACE(p);
    Child node = startNode("lidarcal_rig_none", {"model:=" + rig.string(), p});
    ASSERT_EQ(node.waitExit(20.0).value_or(-1), 2) << node.log();
    const std::string log = node.log();
    EXPECT_NE(log.find(rig.string()), std::string::npos) << log;
    EXPECT_NE(log.find("front (/scan_front), back (/scan)"), std::string::npos) << log;
    EXPECT_NE(log.find(p == "input:=scan_side" ? "'/scan_side'" : "'side'"), std::string::npos)
        << log;
  }
}

TEST_F(Ros2Node, TheSensorDataProfileMatchesAndAPublisherThatComesBackIsServed) {
  const std::vector<io::Ros2LaserScan> sent = scansOf(dir / "in.mcap");
  // input scan, output scan_corrected
  Child node = startNode("lidarcal_restart", {"model:=" + (dir / "model.json").string()});
  peer->subscribe("rt/scan_corrected", PeerQos::sensor_data);
  peer->advertise("rt/scan", PeerQos::sensor_data);
  ASSERT_TRUE(peer->waitMatched(kDiscoveryS)) << node.log();
  prime(sent[0], node);
  publishAll({sent.begin() + 1, sent.begin() + 5}, node);
  const std::size_t before = peer->received().size();
  peer->unadvertise();                               // the driver stops ...
  peer->advertise("rt/scan", PeerQos::sensor_data);  // ... and starts again with a new writer
  ASSERT_TRUE(peer->waitMatched(kDiscoveryS)) << node.log();
  prime(sent[5], node);
  publishAll({sent.begin() + 6, sent.begin() + 10}, node);
  EXPECT_EQ(node.stop(), 0) << node.log();
  const std::vector<Ros2Scan> got = peer->received();
  ASSERT_GE(got.size(), before + 5);
  EXPECT_EQ(got.back().header().stamp().sec(), sent[9].stamp_sec);  // served after the restart
  expectSummaryCounts(node);
}

TEST_F(Ros2Node, DropsMalformedScansCountsThemAndRunsOn) {
  const std::vector<io::Ros2LaserScan> sent = scansOf(dir / "in.mcap");
  Child node = startNode("lidarcal_malformed",
                         {"model:=" + (dir / "model.json").string(), "input_qos:=default"});
  peer->subscribe("rt/scan_corrected", PeerQos::reliable);
  peer->advertise("rt/scan", PeerQos::reliable);
  ASSERT_TRUE(peer->waitMatched(kDiscoveryS)) << node.log();
  prime(sent[0], node);
  std::vector<io::Ros2LaserScan> bad(6, sent[1]);
  bad[0].ranges.clear();  // no beams
  bad[0].intensities.clear();
  bad[1].ranges.resize(kBeams + 1, 3.0f);  // another beam count
  bad[1].intensities.resize(kBeams + 1, 1.0f);
  bad[2].angle_increment = std::numeric_limits<float>::quiet_NaN();
  bad[3].range_max = std::numeric_limits<float>::infinity();
  bad[4].range_min = 20.0f;  // above range_max
  bad[5].intensities.resize(3);
  for (const auto& b : bad) peer->publish(toDds(b));
  publishAll({sent[2]}, node);  // reliable and in order: the malformed ones were handled first
  EXPECT_EQ(node.stop(), 0) << node.log();
  for (const Ros2Scan& got : peer->received())  // only the well-formed scans came out
    EXPECT_TRUE(got.header().stamp().sec() == sent[0].stamp_sec ||
                got.header().stamp().sec() == sent[2].stamp_sec);
  EXPECT_EQ(peer->received().back().header().stamp().sec(), sent[2].stamp_sec);
  expectSummaryCounts(node);
  const std::string log = node.log();
  EXPECT_NE(log.find("6 malformed scans dropped"), std::string::npos) << log;
  EXPECT_NE(log.find("1 another beam count"), std::string::npos) << log;
}

TEST_F(Ros2Node, RefusesAnotherSensorsModelAtTheFirstScan) {
  io::writeModel(dir / "model360.json", polynomialModel("", 360));
  Child node = startNode("lidarcal_refuse",
                         {"model:=" + (dir / "model360.json").string(), "input:=/raw_other"});
  peer->advertise("rt/raw_other", PeerQos::sensor_data);
  ASSERT_TRUE(peer->waitMatched(kDiscoveryS)) << node.log();
  const io::Ros2LaserScan first = scansOf(dir / "in.mcap")[0];
  std::optional<int> status;
  for (int attempt = 0; attempt < 40 && !status; ++attempt) {  // until the node has seen one
    peer->publish(toDds(first));
    status = node.waitExit(0.5);
  }
  ASSERT_TRUE(status) << "the node kept running: " << node.log();
  EXPECT_EQ(*status, 2);
  EXPECT_NE(node.log().find("refusing to correct /raw_other"), std::string::npos) << node.log();
  EXPECT_NE(node.log().find("360"), std::string::npos) << node.log();
}

TEST_F(Ros2Node, HelpAndBadArgumentsAnswerAtOnce) {
  Child help(std::vector<std::string>{LIDARCAL_ROS2_NODE_EXE, "--help"}, dir / "help.log");
  ASSERT_EQ(help.waitExit(20.0).value_or(-1), 0) << help.log();
  for (const char* p : {"model", "input", "output", "inversion", "outside", "sensor_name", "force",
                        "input_qos", "ros_distro", "pose", "ROS_DOMAIN_ID"})
    EXPECT_NE(help.log().find(p), std::string::npos) << p;
  Child no_model = startNode("lidarcal_no_model", {});
  EXPECT_EQ(no_model.waitExit(20.0).value_or(-1), 2) << no_model.log();
  io::writeModel(dir / "named.json", polynomialModel("RPLIDAR A2", static_cast<int>(kBeams)));
  Child named = startNode("lidarcal_named",
                          {"model:=" + (dir / "named.json").string(), "sensor_name:=YDLIDAR X4"});
  EXPECT_EQ(named.waitExit(20.0).value_or(-1), 2) << named.log();
  EXPECT_NE(named.log().find("RPLIDAR A2"), std::string::npos) << named.log();
  Child unknown =
      startNode("lidarcal_unknown", {"model:=" + (dir / "model.json").string(), "colour:=red"});
  EXPECT_EQ(unknown.waitExit(20.0).value_or(-1), 2) << unknown.log();
}

}  // namespace
}  // namespace lidarcal::test
