// lidarcal_node against a real rosmaster (Debian's python3-rosmaster) on loopback, started and
// stopped here: recorded scans published, corrected scans received and compared bit for bit
// with `lidarcal correct IN.bag --out OUT.bag` (the same correction rule); models of another
// sensor refused. Every wait is bounded; processes are ended by their pid.

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>

#include "child_process.hpp"
#include "pipeline/ros_test_util.hpp"
#include "ros/laser_scan_util.hpp"

namespace lidarcal::test {
namespace {

class RosNode : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("lidarcal-ros-node-" + std::to_string(getpid())));
    fs::create_directories(*dir_);
    const int port = freeLoopbackPort();
    ASSERT_GT(port, 0);
    const std::string uri = "http://127.0.0.1:" + std::to_string(port);
    setenv("ROS_MASTER_URI", uri.c_str(), 1);
    setenv("ROS_IP", "127.0.0.1", 1);  // loopback only: rosmaster and the nodes bind to it
    unsetenv("ROS_HOSTNAME");
    setenv("ROS_HOME", dir_->c_str(), 1);
    setenv("ROS_LOG_DIR", dir_->c_str(), 1);
    master_ = new Child({LIDARCAL_ROSMASTER, "--core", "-p", std::to_string(port), "-w", "2"}, *dir_ / "rosmaster.log");
    int argc = 0;
    ros::init(argc, nullptr, "lidarcal_node_test", ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
    ASSERT_TRUE(waitFor([] { return ros::master::check(); }, 30.0)) << "rosmaster did not answer: " << master_->log();
    spinner_ = new ros::AsyncSpinner(1);
    spinner_->start();
  }
  static void TearDownTestSuite() {
    if (spinner_) spinner_->stop();
    delete spinner_;
    ros::shutdown();
    delete master_;  // SIGINT, bounded
    std::error_code ec;
    if (dir_) fs::remove_all(*dir_, ec);
    delete dir_;
  }

  static Child startNode(const std::string& name, const std::vector<std::string>& params) {
    std::vector<std::string> argv = {LIDARCAL_NODE_EXE, "__name:=" + name};
    argv.insert(argv.end(), params.begin(), params.end());
    return Child(argv, *dir_ / (name + ".log"));
  }

  static fs::path* dir_;
  static Child* master_;
  static ros::AsyncSpinner* spinner_;
};
fs::path* RosNode::dir_ = nullptr;
Child* RosNode::master_ = nullptr;
ros::AsyncSpinner* RosNode::spinner_ = nullptr;

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
    const CliResult c = runCli("correct " + (dir / "in.bag").string() + " --model " + (dir / "model.json").string() +
                               " --inversion " + inversion + " -o " + out);
    ASSERT_EQ(c.exit_code, 0) << c.err;
    std::vector<sensor_msgs::LaserScan> in, expected;
    {
      rosbag::Bag a((dir / "in.bag").string(), rosbag::bagmode::Read);
      for (const auto& m : rosbag::View(a)) in.push_back(*m.instantiate<sensor_msgs::LaserScan>());
      rosbag::Bag b(out, rosbag::bagmode::Read);
      for (const auto& m : rosbag::View(b)) expected.push_back(*m.instantiate<sensor_msgs::LaserScan>());
    }
    ASSERT_EQ(expected.size(), in.size());

    const std::string input = "/raw_" + inversion, output = "/corrected_" + inversion;
    // LS from model.json; ML from the model exported as YAML, whose inversion the node takes.
    std::vector<std::string> params = {"_model:=" + (dir / "model.json").string(), "_input:=" + input, "_output:=" + output,
                                       "_inversion:=" + inversion};
    if (inversion == "ml") {
      const fs::path yaml = dir / "model.yaml";
      ASSERT_EQ(runCli("export " + (dir / "model.json").string() + " --format yaml --inversion ml -o " + yaml.string()).exit_code, 0);
      params = {"_model:=" + yaml.string(), "_input:=" + input, "_output:=" + output};
    }
    Child node = startNode("lidarcal_" + inversion, params);
    ros::NodeHandle nh;
    std::mutex mutex;
    std::vector<sensor_msgs::LaserScan> received;
    ros::Subscriber sub = nh.subscribe<sensor_msgs::LaserScan>(output, 100, [&](const sensor_msgs::LaserScan::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex);
      received.push_back(*m);
    });
    ros::Publisher pub = nh.advertise<sensor_msgs::LaserScan>(input, 100);
    ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0; }, 30.0))
        << "the node did not connect: " << node.log();
    for (std::size_t k = 0; k < in.size(); ++k) {
      pub.publish(in[k]);
      ASSERT_TRUE(waitFor([&] { std::lock_guard<std::mutex> lock(mutex); return received.size() > k; }, 10.0))
          << "no corrected scan " << k << ": " << node.log();
    }
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
        EXPECT_TRUE(sameFloat(r.ranges[i], e.ranges[i])) << i << ": " << r.ranges[i] << " vs " << e.ranges[i];
        changed += !sameFloat(r.ranges[i], in[k].ranges[i]);
      }
    }
    EXPECT_GT(changed, in.size() * 50);  // most readings lie in the fitted range and moved
  }
}

TEST_F(RosNode, RefusesAnotherSensorsModelAtTheFirstScan) {
  TempDir dir;
  io::writeModel(dir / "model.json", polynomialModel("", 360));  // a 360-beam sensor's model
  Child node = startNode("lidarcal_refuse", {"_model:=" + (dir / "model.json").string(), "_input:=/raw_other",
                                             "_output:=/corrected_other"});
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

TEST_F(RosNode, HelpPrintsTheParametersWithoutAMaster) {
  TempDir dir;
  // No master at this address: --help must not wait for one.
  for (const char* flag : {"--help", "-h"}) {
    Child help({"env", "ROS_MASTER_URI=http://127.0.0.1:9", LIDARCAL_NODE_EXE, flag}, dir / "help.log");
    ASSERT_EQ(help.waitExit(10.0).value_or(-1), 0) << help.log();
    for (const char* p : {"~model", "~input", "~output", "~inversion", "~outside", "~sensor_name", "~force", "export --format yaml"})
      EXPECT_NE(help.log().find(p), std::string::npos) << p << "\n" << help.log();
  }
}

TEST_F(RosNode, RefusesAtStart) {
  TempDir dir;
  io::writeModel(dir / "model.json", polynomialModel("RPLIDAR A2", 360));
  Child named = startNode("lidarcal_named", {"_model:=" + (dir / "model.json").string(), "_sensor_name:=YDLIDAR X4"});
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
