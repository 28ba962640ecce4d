// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The node tests' fixture: a real rosmaster (Debian's python3-rosmaster) on a free loopback port,
// started once for the suite and stopped at its end, lidarcal_node started as a child process,
// scans sent to it one at a time. Every wait is bounded; processes are ended by their pid.

#include <cstdlib>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>

#include "child_process.hpp"
#include "test_util.hpp"

namespace lidarcal::test {

/// A publisher of scans to a node's input and a subscriber to its output.
class ScanLink {
 public:
  ScanLink(const std::string& input, const std::string& output) {
    sub_ = nh_.subscribe<sensor_msgs::LaserScan>(output, 100,
                                                 [this](const sensor_msgs::LaserScan::ConstPtr& m) {
                                                   std::lock_guard<std::mutex> lock(mutex_);
                                                   received_.push_back(*m);
                                                 });
    pub_ = nh_.advertise<sensor_msgs::LaserScan>(input, 100);
  }
  ScanLink(const ScanLink&) = delete;
  ScanLink& operator=(const ScanLink&) = delete;
  /// Waits until the node is connected both ways; false after 30 s.
  bool connect() {
    return waitFor([&] { return pub_.getNumSubscribers() > 0 && sub_.getNumPublishers() > 0; },
                   30.0);
  }
  /// Publishes `scan` and waits until one more scan came back; false after 10 s.
  bool exchange(const sensor_msgs::LaserScan& scan) {
    const std::size_t before = count();
    pub_.publish(scan);
    return waitFor([&] { return count() > before; }, 10.0);
  }
  std::size_t count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return received_.size();
  }
  std::vector<sensor_msgs::LaserScan> received() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return received_;
  }

 private:
  ros::NodeHandle nh_;
  ros::Publisher pub_;
  ros::Subscriber sub_;
  mutable std::mutex mutex_;
  std::vector<sensor_msgs::LaserScan> received_;
};

/// The value of `key` in a diagnostic status ("" when it has none).
inline std::string valueOf(const diagnostic_msgs::DiagnosticStatus& s, const std::string& key) {
  for (const auto& kv : s.values)
    if (kv.key == key) return kv.value;
  return "";
}

/// The statuses named `name` on /diagnostics, each with the number of scans the test had sent
/// when it arrived.
class DiagnosticsLog {
 public:
  struct Entry {
    diagnostic_msgs::DiagnosticStatus status;
    std::size_t sent = 0;  ///< scans the test had sent when it arrived
  };
  explicit DiagnosticsLog(std::string name) : name_(std::move(name)) {
    sub_ = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          for (const auto& s : m->status)
            if (s.name == name_) entries_.push_back({s, sent_});
        });
  }
  DiagnosticsLog(const DiagnosticsLog&) = delete;
  DiagnosticsLog& operator=(const DiagnosticsLog&) = delete;
  void setSent(std::size_t n) {
    std::lock_guard<std::mutex> lock(mutex_);
    sent_ = n;
  }
  std::vector<Entry> entries() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return entries_;
  }
  /// Waits until a status arrives (after this call) for which `done` holds; false after
  /// `seconds`.
  bool waitFor(const std::function<bool(const diagnostic_msgs::DiagnosticStatus&)>& done,
               double seconds) {
    std::size_t seen = entries().size();
    return test::waitFor(
        [&] {
          const std::vector<Entry> e = entries();
          for (; seen < e.size(); ++seen)
            if (done(e[seen].status)) return true;
          return false;
        },
        seconds);
  }

 private:
  std::string name_;
  ros::NodeHandle nh_;
  ros::Subscriber sub_;
  mutable std::mutex mutex_;
  std::vector<Entry> entries_;
  std::size_t sent_ = 0;
};

class RosNode : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ =
        new fs::path(fs::temp_directory_path() / ("lidarcal-ros-node-" + std::to_string(getpid())));
    fs::create_directories(*dir_);
    const int port = freeLoopbackPort();
    ASSERT_GT(port, 0);
    const std::string uri = "http://127.0.0.1:" + std::to_string(port);
    setenv("ROS_MASTER_URI", uri.c_str(), 1);
    setenv("ROS_IP", "127.0.0.1", 1);  // loopback only: rosmaster and the nodes bind to it
    unsetenv("ROS_HOSTNAME");
    setenv("ROS_HOME", dir_->c_str(), 1);
    setenv("ROS_LOG_DIR", dir_->c_str(), 1);
    master_ = new Child({LIDARCAL_ROSMASTER, "--core", "-p", std::to_string(port), "-w", "2"},
                        *dir_ / "rosmaster.log");
    int argc = 0;
    ros::init(argc, nullptr, "lidarcal_node_test",
              ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
    ASSERT_TRUE(waitFor([] { return ros::master::check(); }, 30.0))
        << "rosmaster did not answer: " << master_->log();
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

  /// Publishes `scans` on `input` to a running node, each after the previous one came back on
  /// `output`; returns the scans received.
  static std::vector<sensor_msgs::LaserScan> correctLive(
      const Child& node, const std::string& input, const std::string& output,
      const std::vector<sensor_msgs::LaserScan>& scans) {
    ScanLink link(input, output);
    if (!link.connect()) {
      ADD_FAILURE() << "the node did not connect: " << node.log();
      return {};
    }
    for (std::size_t k = 0; k < scans.size(); ++k)
      if (!link.exchange(scans[k])) {
        ADD_FAILURE() << "no corrected scan " << k << ": " << node.log();
        break;
      }
    return link.received();
  }

  /// The LaserScans of `topic` in a bag, in order.
  static std::vector<sensor_msgs::LaserScan> scansOf(const fs::path& bag_file,
                                                     const std::string& topic) {
    std::vector<sensor_msgs::LaserScan> out;
    rosbag::Bag bag(bag_file.string(), rosbag::bagmode::Read);
    for (const auto& m : rosbag::View(bag, rosbag::TopicQuery(topic)))
      out.push_back(*m.instantiate<sensor_msgs::LaserScan>());
    return out;
  }

  static inline fs::path* dir_ = nullptr;
  static inline Child* master_ = nullptr;
  static inline ros::AsyncSpinner* spinner_ = nullptr;
};

}  // namespace lidarcal::test
