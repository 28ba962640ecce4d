// SPDX-License-Identifier: BSD-3-Clause
// lidarcal_node in apply mode against a real rosmaster (ros_node_fixture.hpp): recorded scans
// published, corrected scans received and compared bit for bit with `lidarcal correct IN.bag
// --out OUT.bag` (the same correction rule); models of another sensor and bad parameters
// refused; the /diagnostics status. The watch and learn modes: test_ros_node_watch.cpp.

#include <cmath>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include <rosbag/bag.h>
#include <sensor_msgs/LaserScan.h>

#include "pipeline/ros_test_util.hpp"
#include "ros/laser_scan_util.hpp"
#include "ros/ros_node_fixture.hpp"

namespace lidarcal::test {
namespace {

TEST_F(RosNode, PublishesWhatCorrectWritesToABag) {
  TempDir dir;
  // 30 recorded scans, and what `lidarcal correct` makes of them.
  {
    rosbag::Bag bag((dir / "in.bag").string(), rosbag::bagmode::Write);
    for (int k = 0; k < 30; ++k) {
      const sensor_msgs::LaserScan m = laserScan(k, 100);
      bag.write("/scan", m.header.stamp, m);
    }
  }
  io::writeModel(dir / "model.json", polynomialModel("", 100));
  for (const std::string inversion : {"ls", "ml"}) {
    SCOPED_TRACE(inversion);
    const std::string out = (dir / ("out-" + inversion + ".bag")).string();
    const CliResult c =
        runCli("correct " + (dir / "in.bag").string() + " --model " +
               (dir / "model.json").string() + " --inversion " + inversion + " -o " + out);
    ASSERT_EQ(c.exit_code, 0) << c.err;
    const std::vector<sensor_msgs::LaserScan> in = scansOf(dir / "in.bag", "/scan"),
                                              expected = scansOf(out, "/scan");
    ASSERT_EQ(expected.size(), in.size());

    const std::string input = "/raw_" + inversion, output = "/corrected_" + inversion;
    // LS from model.json; ML from the model exported as YAML, whose inversion the node takes.
    std::vector<std::string> params = {"_model:=" + (dir / "model.json").string(),
                                       "_input:=" + input, "_output:=" + output,
                                       "_inversion:=" + inversion};
    if (inversion == "ml") {
      const fs::path yaml = dir / "model.yaml";
      ASSERT_EQ(runCli("export " + (dir / "model.json").string() +
                       " --format yaml --inversion ml -o " + yaml.string())
                    .exit_code,
                0);
      params = {"_model:=" + yaml.string(), "_input:=" + input, "_output:=" + output};
    }
    Child node = startNode("lidarcal_" + inversion, params);
    const std::vector<sensor_msgs::LaserScan> received = correctLive(node, input, output, in);
    EXPECT_EQ(node.stop(), 0) << node.log();
    EXPECT_NE(node.log().find("30 scans"), std::string::npos) << node.log();
    ASSERT_EQ(received.size(), expected.size());
    std::size_t changed = 0;
    for (std::size_t k = 0; k < received.size(); ++k) {
      SCOPED_TRACE(k);
      const auto& r = received[k];
      const auto& e = expected[k];
      expectSameScanButRanges(r, e);
      ASSERT_EQ(r.ranges.size(), e.ranges.size());
      for (std::size_t i = 0; i < r.ranges.size(); ++i) {
        EXPECT_TRUE(sameFloat(r.ranges[i], e.ranges[i]))
            << i << ": " << r.ranges[i] << " vs " << e.ranges[i];
        changed += !sameFloat(r.ranges[i], in[k].ranges[i]);
      }
    }
    EXPECT_GT(changed, in.size() * 50);  // most readings lie in the fitted range and moved
  }
}

TEST_F(RosNode, RefusesAnotherSensorsModelAtTheFirstScan) {
  TempDir dir;
  io::writeModel(dir / "model.json", polynomialModel("", 360));  // a 360-beam sensor's model
  Child node = startNode("lidarcal_refuse", {"_model:=" + (dir / "model.json").string(),
                                             "_input:=/raw_other", "_output:=/corrected_other"});
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::LaserScan>("/raw_other", 10);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }, 30.0)) << node.log();
  pub.publish(laserScan(0, 100));
  const auto status = node.waitExit(20.0);
  ASSERT_TRUE(status) << "the node kept running: " << node.log();
  EXPECT_EQ(*status, 2);
  const std::string log = node.log();
  EXPECT_NE(log.find("refusing to correct /raw_other"), std::string::npos) << log;
  EXPECT_NE(log.find("360"), std::string::npos) << log;
}

TEST_F(RosNode, PicksTheBlockOfARigModelByTopicOrSensorName) {
  TempDir dir;
  // A two-lidar bag and a rig model whose blocks differ; `correct` applies each block to its topic.
  {
    rosbag::Bag bag((dir / "in.bag").string(), rosbag::bagmode::Write);
    for (int k = 0; k < 8; ++k)
      for (const char* topic : {"/scan_front", "/scan_back"}) {
        const sensor_msgs::LaserScan m = laserScan(k, 100);
        bag.write(topic, m.header.stamp, m);
      }
  }
  const fs::path rig = dir / "rig.json";
  io::writeRigModel(rig, twoLidarModel("/scan_front", "/scan_back"));
  const CliResult c = runCli("correct " + (dir / "in.bag").string() + " --model " + rig.string() +
                             " -o " + (dir / "out.bag").string());
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const std::vector<sensor_msgs::LaserScan> in = scansOf(dir / "in.bag", "/scan_back");
  const std::vector<sensor_msgs::LaserScan> front = scansOf(dir / "out.bag", "/scan_front"),
                                            back = scansOf(dir / "out.bag", "/scan_back");
  ASSERT_EQ(in.size(), 8u);
  ASSERT_EQ(back.size(), 8u);
  ASSERT_FALSE(sameFloat(front[0].ranges[50], back[0].ranges[50]));  // the blocks tell apart

  // By the input topic (the block's), and by ~sensor_name on another topic.
  struct Case {
    std::string name, input, block;
    std::vector<std::string> extra;
  };
  for (const Case& k : {Case{"lidarcal_rig_topic", "/scan_back", "back", {}},
                        Case{"lidarcal_rig_name", "/raw_rig", "front", {"_sensor_name:=front"}}}) {
    SCOPED_TRACE(k.name);
    std::vector<std::string> params = {"_model:=" + rig.string(), "_input:=" + k.input,
                                       "_output:=/corrected_rig"};
    params.insert(params.end(), k.extra.begin(), k.extra.end());
    Child node = startNode(k.name, params);
    const std::vector<sensor_msgs::LaserScan> received =
        correctLive(node, k.input, "/corrected_rig", in);
    EXPECT_EQ(node.stop(), 0) << node.log();
    EXPECT_NE(node.log().find("block " + k.block), std::string::npos) << node.log();
    const std::vector<sensor_msgs::LaserScan>& expected = k.block == "back" ? back : front;
    ASSERT_EQ(received.size(), expected.size());
    for (std::size_t s = 0; s < received.size(); ++s)
      for (std::size_t i = 0; i < received[s].ranges.size(); ++i)
        EXPECT_TRUE(sameFloat(received[s].ranges[i], expected[s].ranges[i])) << s << "/" << i;
  }

  // No block for the topic or the name: refused at start, the blocks listed.
  for (const std::vector<std::string>& p :
       {std::vector<std::string>{"_input:=/scan_side"},
        std::vector<std::string>{"_input:=/scan_back", "_sensor_name:=side"}}) {
    std::vector<std::string> params = {"_model:=" + rig.string()};
    params.insert(params.end(), p.begin(), p.end());
    Child node = startNode("lidarcal_rig_none", params);
    ASSERT_EQ(node.waitExit(20.0).value_or(-1), 2) << node.log();
    const std::string log = node.log();
    EXPECT_NE(log.find(rig.string()), std::string::npos) << log;
    EXPECT_NE(log.find("front (/scan_front), back (/scan_back)"), std::string::npos) << log;
    EXPECT_NE(log.find(p.size() == 1 ? "'/scan_side'" : "'side'"), std::string::npos) << log;
  }
}

TEST_F(RosNode, HelpPrintsTheParametersWithoutAMaster) {
  TempDir dir;
  // No master at this address: --help must not wait for one.
  for (const char* flag : {"--help", "-h"}) {
    Child help({"env", "ROS_MASTER_URI=http://127.0.0.1:9", LIDARCAL_NODE_EXE, flag},
               dir / "help.log");
    ASSERT_EQ(help.waitExit(10.0).value_or(-1), 0) << help.log();
    for (const char* p :
         {"~model", "~input", "~output", "~inversion", "~outside", "~sensor_name", "~force",
          "export --format yaml", "~mode", "~false_alarms", "~false_alarms_per", "~check_every",
          "~check_bias_replicas", "~landmark_radius", "~pose", "~candidate_topic",
          "~candidate_file", "~diagnostics_period"})
      EXPECT_NE(help.log().find(p), std::string::npos) << p << "\n" << help.log();
  }
}

TEST_F(RosNode, PublishesAnOkStatusInApplyMode) {
  TempDir dir;
  io::writeModel(dir / "model.json", polynomialModel("RPLIDAR A2", 100));
  DiagnosticsLog diagnostics("lidarcal: range model of /raw_diag");
  Child node =
      startNode("lidarcal_diag", {"_model:=" + (dir / "model.json").string(), "_input:=/raw_diag",
                                  "_output:=/corrected_diag", "_diagnostics_period:=0.2"});
  std::vector<sensor_msgs::LaserScan> scans;
  for (int k = 0; k < 5; ++k) scans.push_back(laserScan(k, 100));
  ASSERT_EQ(correctLive(node, "/raw_diag", "/corrected_diag", scans).size(), scans.size());
  ASSERT_TRUE(diagnostics.waitFor(
      [](const diagnostic_msgs::DiagnosticStatus& s) {
        return valueOf(s, "scans received") == "5";
      },
      20.0))
      << node.log();
  const diagnostic_msgs::DiagnosticStatus last = diagnostics.entries().back().status;
  EXPECT_EQ(last.level, diagnostic_msgs::DiagnosticStatus::OK) << last.message;
  EXPECT_EQ(last.hardware_id, "RPLIDAR A2");
  EXPECT_EQ(valueOf(last, "mode"), "apply");
  EXPECT_NE(last.message.find((dir / "model.json").string()), std::string::npos) << last.message;
  // Every reading of the 5 scans (95 of 100 beams each: laserScan) is accounted for, most
  // corrected.
  const std::size_t corrected = std::stoul(valueOf(last, "returns corrected"));
  EXPECT_EQ(corrected +
                std::stoul(valueOf(last, "returns beyond the fitted range left uncorrected")) +
                std::stoul(valueOf(last, "returns without a distance")),
            5u * 95u);
  EXPECT_GT(corrected, 5u * 50u);
  EXPECT_EQ(node.stop(), 0) << node.log();
}

TEST_F(RosNode, RefusesAtStart) {
  TempDir dir;
  io::writeModel(dir / "model.json", polynomialModel("RPLIDAR A2", 360));
  Child named = startNode("lidarcal_named",
                          {"_model:=" + (dir / "model.json").string(), "_sensor_name:=YDLIDAR X4"});
  const auto status = named.waitExit(20.0);
  ASSERT_TRUE(status) << named.log();
  EXPECT_EQ(*status, 2);
  EXPECT_NE(named.log().find("RPLIDAR A2"), std::string::npos) << named.log();
  Child no_model = startNode("lidarcal_no_model", {});
  ASSERT_EQ(no_model.waitExit(20.0).value_or(-1), 2) << no_model.log();
  EXPECT_NE(no_model.log().find("~model"), std::string::npos) << no_model.log();
  CalibrationModel turning = polynomialModel("", 0);
  turning.model.bias.alpha = {0.0, 1.0, -0.1};  // turns back inside the fitted range
  io::writeModel(dir / "turning.json", turning);
  Child bad = startNode("lidarcal_turning", {"_model:=" + (dir / "turning.json").string()});
  ASSERT_EQ(bad.waitExit(20.0).value_or(-1), 3) << bad.log();
}

}  // namespace
}  // namespace lidarcal::test
