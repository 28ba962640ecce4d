// SPDX-License-Identifier: BSD-3-Clause
// lidarcal_node's watch and learn modes against a real rosmaster (ros_node_fixture.hpp): a
// simulated drive (tests/watch/drive.hpp) published as a robot's topics, the scans as LaserScan
// and the odometry's poses as nav_msgs/Odometry on /odom, with a 20 mm offset injected part way.
// The node's /diagnostics, log, candidate models and corrected scans are checked against the
// change the test made and the simulator's true range of every beam.

#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <mutex>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <nav_msgs/Odometry.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include "io/model_io.hpp"
#include "pipeline/ros_test_util.hpp"
#include "ros/laser_scan_util.hpp"
#include "ros/ros_node_fixture.hpp"
#include "watch/drive.hpp"

namespace lidarcal::test {
namespace {

using diagnostic_msgs::DiagnosticStatus;

constexpr std::uint64_t kSeed = 51;
constexpr double kStartS = 1000.0;         // stamp of scan 0 (ROS times are positive)
constexpr std::size_t kChangeAt = 900;     // the first scan read 20 mm long
constexpr std::size_t kOdometryAhead = 3;  // odometry sent this many scans before its scan
constexpr std::size_t kWatcherBehind =
    24;  // scans the watcher may lag the correction by (< its queue)

/// The true range of one beam that hit a pole.
struct PoleBeam {
  std::size_t beam = 0;
  double range_m = 0.0;
};

/// Scan i of the drive as the robot's topics carry it (frame "laser", stamped kStartS + 0.1 i),
/// and the true range of its beams on poles.
struct DriveStep {
  sensor_msgs::LaserScan scan;
  nav_msgs::Odometry odometry;  ///< the odometry's pose of the sensor, odom -> laser
  std::vector<PoleBeam> poles;
};

DriveStep driveStep(const Scene& scene, const std::vector<TruthStop>& stops, std::size_t i) {
  const io::RawScan raw = driveScan(scene, stops, i, kSeed, watch::parseRangeChange("20@900"));
  DriveStep d;
  d.scan.header.stamp = ros::Time(kStartS + raw.stamp_s);
  d.scan.header.frame_id = "laser";
  d.scan.angle_min = static_cast<float>(scene.sensor.angle_min_rad);
  d.scan.angle_increment = static_cast<float>(scene.sensor.angle_increment_rad);
  d.scan.angle_max =
      d.scan.angle_min + d.scan.angle_increment * static_cast<float>(raw.ranges_m.size() - 1);
  d.scan.range_min = static_cast<float>(raw.range_min_m);
  d.scan.range_max = static_cast<float>(raw.range_max_m);
  d.scan.ranges = raw.ranges_m;
  d.odometry.header.stamp = d.scan.header.stamp;
  d.odometry.header.frame_id = "odom";
  d.odometry.child_frame_id = "laser";
  d.odometry.pose.pose.position.x = raw.pose.x_m;
  d.odometry.pose.pose.position.y = raw.pose.y_m;
  d.odometry.pose.pose.orientation.z = std::sin(0.5 * raw.pose.yaw_rad);
  d.odometry.pose.pose.orientation.w = std::cos(0.5 * raw.pose.yaw_rad);
  for (const io::TrueRange& t : simulation::simulateScan(scene, stops[i], i, kSeed).truth)
    if (t.target == io::TargetKind::landmark && std::isfinite(t.range_m))
      d.poles.push_back({t.beam, t.range_m});
  return d;
}

/// What a drive through the node gave.
struct DriveRun {
  std::vector<sensor_msgs::LaserScan> corrected;  ///< the node's output, in order
  std::vector<std::vector<PoleBeam>> poles;       ///< the truth of each scan's pole beams
};

/// Publishes `scans` scans of the drive to a node reading /scan_<tag> and /odom: each scan after
/// the node corrected the previous one and while its watcher is at most kWatcherBehind scans
/// behind (from its /diagnostics), so that it watches every scan as it would at 10 Hz.
DriveRun drive(const Child& node, const std::string& tag, std::size_t scans,
               DiagnosticsLog& diagnostics) {
  const Scene scene = drivingScene("driving_large_poles", scans);
  const auto stops = simulation::planStops(scene, kSeed);
  ScanLink link("/scan_" + tag, "/corrected_" + tag);
  ros::NodeHandle nh;
  ros::Publisher odometry = nh.advertise<nav_msgs::Odometry>("/odom", 100);
  DriveRun run;
  if (!link.connect() || !waitFor([&] { return odometry.getNumSubscribers() > 0; }, 30.0)) {
    ADD_FAILURE() << "the node did not connect: " << node.log();
    return run;
  }
  std::vector<DriveStep> ahead;  // scans whose odometry was sent, not yet the scans
  for (std::size_t k = 0; k < scans; ++k) {
    while (ahead.size() <= kOdometryAhead && k + ahead.size() < scans) {
      ahead.push_back(driveStep(scene, stops, k + ahead.size()));
      odometry.publish(ahead.back().odometry);
    }
    diagnostics.setSent(k + 1);
    if (!link.exchange(ahead.front().scan)) {
      ADD_FAILURE() << "no corrected scan " << k << ": " << node.log();
      break;
    }
    run.poles.push_back(std::move(ahead.front().poles));
    ahead.erase(ahead.begin());
    const auto watched = [&](const DiagnosticStatus& s) {
      return std::stoul("0" + valueOf(s, "scans watched")) + kWatcherBehind > k;
    };
    const auto entries = diagnostics.entries();
    if ((entries.empty() || !watched(entries.back().status)) &&
        !diagnostics.waitFor(watched, 60.0)) {
      ADD_FAILURE() << "the watcher fell behind at scan " << k << ": " << node.log();
      break;
    }
  }
  run.corrected = link.received();
  return run;
}

/// Mean of corrected minus true range over the pole beams of scans [first, last) whose true
/// range lies in [lo, hi] metres; NaN without any.
double meanError(const DriveRun& run, std::size_t first, std::size_t last, double lo, double hi) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t k = first; k < last && k < run.corrected.size(); ++k)
    for (const PoleBeam& p : run.poles[k]) {
      const float r = run.corrected[k].ranges[p.beam];
      if (!std::isfinite(r) || p.range_m < lo || p.range_m > hi) continue;
      sum += static_cast<double>(r) - p.range_m;
      ++n;
    }
  return n ? sum / static_cast<double>(n) : NAN;
}

/// The scene's sensor as model.json (zero standard errors: the model matches the sensor exactly
/// until the change).
fs::path writeTrueModel(const TempDir& dir) {
  const fs::path file = dir / "model.json";
  io::writeModel(file, *trueModel(drivingScene("driving_large_poles", 10)));
  return file;
}

/// The first scan the test had sent when a status satisfying `pred` arrived (none: SIZE_MAX).
std::size_t firstSent(const std::vector<DiagnosticsLog::Entry>& entries,
                      const std::function<bool(const DiagnosticStatus&)>& pred) {
  for (const auto& e : entries)
    if (pred(e.status)) return e.sent;
  return SIZE_MAX;
}

bool isError(const DiagnosticStatus& s) { return s.level == DiagnosticStatus::ERROR; }

/// The scans a status counts as watched or left out of watching.
std::size_t watchedOrNot(const DiagnosticStatus& s) {
  return std::stoul("0" + valueOf(s, "scans watched")) +
         std::stoul("0" + valueOf(s, "scans not watched"));
}

std::string readText(const fs::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST_F(RosNode, WatchModeTurnsToErrorAfterAChangeOfTheSensor) {
  TempDir dir;
  const fs::path model = writeTrueModel(dir);
  DiagnosticsLog diagnostics("lidarcal: range model of /scan_watch");
  Child node = startNode("lidarcal_watch", {"_model:=" + model.string(), "_input:=/scan_watch",
                                            "_output:=/corrected_watch", "_mode:=watch",
                                            "_landmark_radius:=0.1", "_diagnostics_period:=0.1"});
  const DriveRun run = drive(node, "watch", 1200, diagnostics);
  ASSERT_EQ(run.corrected.size(), 1200u);
  ASSERT_TRUE(diagnostics.waitFor(isError, 60.0)) << "no ERROR after the change: " << node.log();
  // Every scan watched, but the first may arrive before the first odometry (its own connection).
  ASSERT_TRUE(
      diagnostics.waitFor([](const DiagnosticStatus& s) { return watchedOrNot(s) == 1200; }, 60.0))
      << node.log();
  const auto entries = diagnostics.entries();
  // OK once the baseline was tested, and ERROR only once the changed scans were sent.
  EXPECT_LT(
      firstSent(entries, [](const DiagnosticStatus& s) { return s.level == DiagnosticStatus::OK; }),
      kChangeAt);
  EXPECT_GT(firstSent(entries, isError), kChangeAt);
  const DiagnosticStatus last = entries.back().status;
  EXPECT_LE(std::stoul(valueOf(last, "scans not watched")), 1u) << node.log();
  EXPECT_EQ(valueOf(last, "mode"), "watch");
  EXPECT_NE(last.message.find("the sensor has changed"), std::string::npos) << last.message;
  EXPECT_EQ(node.stop(), 0) << node.log();
  // The alarm in the log, with its evidence, at a scan after the change.
  const std::string log = node.log();
  std::smatch m;
  ASSERT_TRUE(std::regex_search(log, m,
                                std::regex("alarm at scan ([0-9]+) .*the sensor changed: "
                                           "shift [-+][0-9.]+ \\+- [0-9.]+ mm")))
      << log;
  EXPECT_GE(std::stoul(m[1]), kChangeAt);
  // Watch mode never changes the correction: the pole readings read 20 mm / f'(d) long after.
  EXPECT_NEAR(meanError(run, 200, kChangeAt, 0.0, 10.0), 0.0, 0.002);
  EXPECT_GT(meanError(run, kChangeAt + 10, 1200, 0.0, 10.0), 0.015);
}

TEST_F(RosNode, LearnModeSwitchesAndTheCorrectedScansFollow) {
  TempDir dir;
  const fs::path model = writeTrueModel(dir);
  const fs::path candidate_file = dir / "candidate.json";
  DiagnosticsLog diagnostics("lidarcal: range model of /scan_learn");
  std::mutex mutex;
  std::vector<std::string> candidates;
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe<std_msgs::String>("/lidarcal_learn/candidate_model", 10,
                                                       [&](const std_msgs::String::ConstPtr& m) {
                                                         std::lock_guard<std::mutex> lock(mutex);
                                                         candidates.push_back(m->data);
                                                       });
  Child node = startNode("lidarcal_learn", {"_model:=" + model.string(), "_input:=/scan_learn",
                                            "_output:=/corrected_learn", "_mode:=learn",
                                            "_landmark_radius:=0.1", "_diagnostics_period:=0.1",
                                            "_candidate_file:=" + candidate_file.string()});
  const DriveRun run = drive(node, "learn", 2000, diagnostics);
  ASSERT_EQ(run.corrected.size(), 2000u);
  const auto switched = [](const DiagnosticStatus& s) { return valueOf(s, "switches") == "1"; };
  diagnostics.waitFor(switched, 60.0);
  const auto entries = diagnostics.entries();
  const std::size_t switch_sent = firstSent(entries, switched);
  ASSERT_LT(switch_sent, 1800u) << "no switch with 200 scans to spare: " << node.log();
  EXPECT_GT(firstSent(entries, isError), kChangeAt);
  EXPECT_LT(firstSent(entries, isError), switch_sent);
  EXPECT_NE(entries.back().status.level, DiagnosticStatus::ERROR) << entries.back().status.message;
  EXPECT_EQ(node.stop(), 0) << node.log();

  // The switch in the log with both models; every candidate on the topic, the last in the file.
  const std::string log = node.log();
  EXPECT_TRUE(std::regex_search(log, std::regex("switch at scan [0-9]+ .* to model 2: .*Bias of "
                                                "the model before: at 1 m .*now: at 1 m")))
      << log;
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_FALSE(candidates.empty());
  EXPECT_EQ(readText(candidate_file), candidates.back());
  const CalibrationModel learnt = io::readModel(candidate_file);
  ASSERT_TRUE(learnt.status.ok()) << learnt.status.message;
  ASSERT_TRUE(learnt.fitted_range_m);
  const auto [lo, hi] = *learnt.fitted_range_m;

  // The corrected pole readings: unbiased before the change, 20 mm / f'(d) long after it under
  // the old model, unbiased again once the node corrects with the learnt one (its corrector is
  // built beside the scans, in use a scan or two after the switch).
  const std::size_t learnt_from = switch_sent + 5;
  EXPECT_NEAR(meanError(run, 200, kChangeAt, lo, hi), 0.0, 0.002);
  EXPECT_GT(meanError(run, kChangeAt + 10, std::min(switch_sent, kChangeAt + 200), lo, hi), 0.015);
  const double after = meanError(run, learnt_from, run.corrected.size(), lo, hi);
  EXPECT_NEAR(after, 0.0, 0.004) << "fitted " << lo << "-" << hi << " m";
  EXPECT_NEAR(meanError(run, learnt_from, run.corrected.size(), lo, 0.5 * (lo + hi)), 0.0, 0.004);
  EXPECT_NEAR(meanError(run, learnt_from, run.corrected.size(), 0.5 * (lo + hi), hi), 0.0, 0.004);
}

TEST_F(RosNode, WatchesWithPosesFromTf) {
  TempDir dir;
  const fs::path model = writeTrueModel(dir);
  DiagnosticsLog diagnostics("lidarcal: range model of /scan_tf");
  Child node = startNode("lidarcal_tf",
                         {"_model:=" + model.string(), "_input:=/scan_tf", "_output:=/corrected_tf",
                          "_mode:=watch", "_pose:=tf:map", "_diagnostics_period:=0.1"});
  ros::NodeHandle nh;
  ros::Publisher tf = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
  ros::Publisher tf_static = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 1, /*latch=*/true);
  ScanLink link("/scan_tf", "/corrected_tf");
  ASSERT_TRUE(link.connect() && waitFor([&] { return tf.getNumSubscribers() > 0; }, 30.0))
      << node.log();
  // map -> odom fixed (static), odom -> laser the odometry's pose of each scan (moving).
  const auto transform = [](const std::string& parent, const nav_msgs::Odometry& o) {
    geometry_msgs::TransformStamped t;
    t.header.stamp = o.header.stamp;
    t.header.frame_id = parent;
    t.child_frame_id = o.child_frame_id;
    t.transform.translation.x = o.pose.pose.position.x;
    t.transform.translation.y = o.pose.pose.position.y;
    t.transform.rotation = o.pose.pose.orientation;
    return t;
  };
  tf2_msgs::TFMessage fixed;
  nav_msgs::Odometry map_to_odom;
  map_to_odom.child_frame_id = "odom";
  map_to_odom.pose.pose.position.x = 2.0;
  map_to_odom.pose.pose.orientation.w = 1.0;
  fixed.transforms.push_back(transform("map", map_to_odom));
  tf_static.publish(fixed);
  const Scene scene = drivingScene("driving_large_poles", 30);
  const auto stops = simulation::planStops(scene, kSeed);
  std::vector<DriveStep> steps;
  for (std::size_t i = 0; i < stops.size(); ++i) steps.push_back(driveStep(scene, stops, i));
  std::size_t moved = 0;  // scans whose odom -> laser transform was sent: one scan ahead
  for (std::size_t i = 0; i < steps.size(); ++i) {
    for (; moved < std::min(i + 2, steps.size()); ++moved) {
      tf2_msgs::TFMessage moving;
      moving.transforms.push_back(transform("odom", steps[moved].odometry));
      tf.publish(moving);
    }
    ASSERT_TRUE(link.exchange(steps[i].scan)) << node.log();
  }
  ASSERT_TRUE(diagnostics.waitFor(
      [&](const DiagnosticStatus& s) { return watchedOrNot(s) == steps.size(); }, 30.0))
      << node.log();
  // The first scan may arrive before the first transforms (their own connections).
  EXPECT_LE(std::stoul(valueOf(diagnostics.entries().back().status, "scans not watched")), 1u)
      << node.log();
  EXPECT_EQ(node.stop(), 0) << node.log();
}

TEST_F(RosNode, LeavesScansWithoutAPoseOrMalformedOutOfWatchingAndKeepsRunning) {
  TempDir dir;
  DiagnosticsLog diagnostics("lidarcal: range model of /scan_nopose");
  // Learn mode without a model: the scans pass as they came until a model is learnt.
  Child node = startNode("lidarcal_nopose",
                         {"_input:=/scan_nopose", "_output:=/corrected_nopose", "_mode:=learn",
                          "_pose:=odom:/odom_nopose", "_diagnostics_period:=0.1"});
  ros::NodeHandle nh;
  ros::Publisher odometry = nh.advertise<nav_msgs::Odometry>("/odom_nopose", 10);
  ScanLink link("/scan_nopose", "/corrected_nopose");
  ASSERT_TRUE(link.connect() && waitFor([&] { return odometry.getNumSubscribers() > 0; }, 30.0))
      << node.log();
  nav_msgs::Odometry broken;
  broken.header.stamp = ros::Time(100);
  broken.header.frame_id = "odom";
  broken.child_frame_id = "laser";
  broken.pose.pose.position.x = NAN;
  odometry.publish(broken);
  std::vector<sensor_msgs::LaserScan> sent;
  for (int k = 0; k < 3; ++k) sent.push_back(laserScan(k, 100));
  sent.push_back(laserScan(3, 100));
  sent.back().angle_increment = NAN;
  sent.push_back(laserScan(4, 100));
  sent.back().ranges.clear();
  sent.back().intensities.clear();
  for (const auto& s : sent) ASSERT_TRUE(link.exchange(s)) << node.log();
  ASSERT_TRUE(diagnostics.waitFor(
      [](const DiagnosticStatus& s) { return valueOf(s, "scans not watched") == "5"; }, 20.0))
      << node.log();
  const DiagnosticStatus last = diagnostics.entries().back().status;
  EXPECT_EQ(last.level, DiagnosticStatus::WARN) << last.message;
  EXPECT_EQ(valueOf(last, "scans without a pose"), "3");
  EXPECT_EQ(valueOf(last, "scans passed uncorrected (no model yet)"), "5");
  const std::vector<sensor_msgs::LaserScan> received = link.received();
  ASSERT_EQ(received.size(), sent.size());
  for (std::size_t k = 0; k < sent.size(); ++k) {
    ASSERT_EQ(received[k].ranges.size(), sent[k].ranges.size());
    for (std::size_t i = 0; i < sent[k].ranges.size(); ++i)
      EXPECT_TRUE(sameFloat(received[k].ranges[i], sent[k].ranges[i])) << k << "/" << i;
  }
  EXPECT_EQ(node.stop(), 0) << node.log();
  EXPECT_NE(node.log().find("odometry message dropped"), std::string::npos) << node.log();
  EXPECT_NE(node.log().find("not watched"), std::string::npos) << node.log();
}

TEST_F(RosNode, RefusesBadWatchParametersAtStart) {
  TempDir dir;
  const fs::path model = writeTrueModel(dir);
  io::writeModel(dir / "no_covariance.json", polynomialModel("", 0));
  struct Case {
    std::vector<std::string> params;
    std::string named;  // in the ROS_FATAL line
  };
  const std::string m = "_model:=" + model.string();
  int n = 0;
  for (const Case& c :
       {Case{{m, "_mode:=sometimes"}, "~mode"},
        Case{{m, "_mode:=watch", "_false_alarms:=-1"}, "~false_alarms"},
        Case{{m, "_mode:=watch", "_false_alarms:=often"}, "~false_alarms"},
        Case{{m, "_mode:=watch", "_false_alarms_per:=week"}, "~false_alarms_per"},
        Case{{m, "_mode:=watch", "_check_every:=0"}, "~check_every"},
        Case{{m, "_mode:=watch", "_check_bias_replicas:=-1"}, "~check_bias_replicas"},
        Case{{m, "_mode:=watch", "_landmark_radius:=-0.1"}, "~landmark_radius"},
        Case{{m, "_mode:=watch", "_pose:=gps"}, "~pose"},
        Case{{m, "_mode:=learn", "_candidate_file:=" + (dir / "missing" / "c.json").string()},
             "~candidate_file"},
        Case{{m, "_mode:=watch", "_diagnostics_period:=0"}, "~diagnostics_period"},
        Case{{"_mode:=watch"}, "~model"},
        Case{{"_model:=" + (dir / "no_covariance.json").string(), "_mode:=watch"},
             "alpha_covariance"}}) {
    // A name of its own per case: the parameters of a node stay on the master after it ends.
    Child node = startNode("lidarcal_bad" + std::to_string(++n), c.params);
    ASSERT_EQ(node.waitExit(20.0).value_or(-1), 2) << node.log();
    EXPECT_NE(node.log().find(c.named), std::string::npos) << node.log();
  }
}

}  // namespace
}  // namespace lidarcal::test
