// SPDX-License-Identifier: BSD-3-Clause
// The ROS 2 node without DDS: its command line (ROS 2's -p/-r syntax, name resolution, the
// release and pose source, the node's names, the watch modes' parameters and the watcher's
// settings made from them), the per-scan rule (ros2::LiveCorrector against
// pipeline::correctLaserRanges, the rule of `correct`; in learn mode also without a model yet),
// the rate limit of its warnings, and the model read from export's YAML.

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "io/model_yaml.hpp"
#include "pipeline/ros_test_util.hpp"
#include "pipeline/stages/model_export.hpp"
#include "ros2/live_corrector.hpp"
#include "ros2/node_args.hpp"
#include "ros2/warning_limiter.hpp"
#include "ros2/watched_corrector.hpp"

namespace lidarcal::test {
namespace {

ros2::NodeParameters parse(std::vector<const char*> args) {
  args.insert(args.begin(), "lidarcal_ros2_node");
  return ros2::parseNodeArguments(static_cast<int>(args.size()), args.data());
}

TEST(Ros2NodeArguments, RosArgsParametersAndRemapsAsRos2TakesThem) {
  const ros2::NodeParameters p = parse(
      {"--ros-args", "-p", "model:=/m.json", "-p", "input:=laser", "--param", "output:='fixed'",
       "-p", "inversion:=ml", "-p", "force:=true", "-p", "input_qos:=default", "-r",
       "__node:=front", "-r", "__ns:=/robot", "-r", "laser:=/front/scan"});
  EXPECT_EQ(p.model_file, "/m.json");
  EXPECT_EQ(*p.inversion, "ml");
  EXPECT_TRUE(p.force);
  EXPECT_EQ(p.input_qos, ros2::QosProfile::reliable);
  EXPECT_EQ(p.node_name, "front");
  EXPECT_EQ(ros2::resolveTopic(p.input, p), "/front/scan");    // remapped
  EXPECT_EQ(ros2::resolveTopic(p.output, p), "/robot/fixed");  // relative to the namespace
  EXPECT_EQ(ros2::resolveTopic("~/diag", p), "/robot/front/diag");
  EXPECT_EQ(ros2::ddsTopicName("/robot/fixed"), "rt/robot/fixed");
  const ros2::NodeParameters d = parse({"--ros-args", "-p", "model:=m.json"});
  EXPECT_EQ(ros2::ddsTopicName(ros2::resolveTopic(d.input, d)), "rt/scan");
  EXPECT_EQ(ros2::ddsTopicName(ros2::resolveTopic(d.output, d)), "rt/scan_corrected");
  EXPECT_EQ(d.input_qos, ros2::QosProfile::sensor_data);
  EXPECT_FALSE(d.outside.has_value());
}

TEST(Ros2NodeArguments, HelpNeedsNothingElseAndMistakesAreInputErrors) {
  EXPECT_TRUE(parse({"--help"}).help);
  EXPECT_TRUE(parse({"--ros-args", "-p", "model:=m", "--", "-h"}).help);  // after the ROS arguments
  for (const auto& bad : std::vector<std::vector<const char*>>{
           {"--ros-args"},                                            // no model
           {"--ros-args", "-p", "model:=m", "-p", "colour:=red"},     // unknown parameter
           {"--ros-args", "-p", "model"},                             // not NAME:=VALUE
           {"--ros-args", "-p", "model:=m", "-p", "inversion:=x"},    // not ls/ml
           {"--ros-args", "-p", "model:=m", "-p", "outside:=maybe"},  // not a policy
           {"--ros-args", "-p", "model:=m", "-p", "force:=yes"},      // not a boolean
           {"--ros-args", "-p", "model:=m", "-r", "__ns:=robot"},     // relative namespace
           {"-p", "model:=m"},                                        // outside --ros-args
       }) {
    EXPECT_THROW(parse(bad), InputError) << bad.back();
  }
  const ros2::NodeParameters p = parse({"--ros-args", "-p", "model:=m", "-p", "input:=bad name"});
  EXPECT_THROW(ros2::resolveTopic(p.input, p), InputError);
}

TEST(Ros2NodeArguments, RosDistroPoseSourceAndTheNodesNames) {
  const ros2::NodeParameters d = parse({"--ros-args", "-p", "model:=m"});
  EXPECT_EQ(d.ros_distro, ros2::RosDistro::humble);
  EXPECT_EQ(d.pose.kind, ros2::PoseSource::Kind::odom);
  EXPECT_EQ(ros2::resolveTopic(d.pose.name, d), "/odom");
  EXPECT_EQ(ros2::fullyQualifiedNodeName(d), "/lidarcal");
  EXPECT_EQ(ros2::loggerName(d), "lidarcal");
  // rmw_dds_common's Gid.msg: char[24] up to humble, char[16] from iron on.
  for (const auto& [name, bytes] : std::vector<std::pair<const char*, std::size_t>>{
           {"foxy", 24}, {"humble", 24}, {"iron", 16}, {"jazzy", 16}, {"rolling", 16}}) {
    const ros2::RosDistro r = ros2::parseRosDistro(name);
    EXPECT_EQ(std::string(ros2::toString(r)), name);
    EXPECT_EQ(ros2::gidBytes(r), bytes) << name;
  }
  const ros2::NodeParameters p =
      parse({"--ros-args", "-p", "model:=m", "-p", "ros_distro:=jazzy", "-p", "pose:=tf:/map", "-r",
             "__ns:=/fleet/robot1", "-r", "__node:=front_lidar"});
  EXPECT_EQ(p.ros_distro, ros2::RosDistro::jazzy);
  EXPECT_EQ(p.pose.kind, ros2::PoseSource::Kind::tf);
  EXPECT_EQ(p.pose.name, "map");  // a frame: no leading slash
  EXPECT_EQ(ros2::fullyQualifiedNodeName(p), "/fleet/robot1/front_lidar");
  EXPECT_EQ(ros2::loggerName(p), "fleet.robot1.front_lidar");  // as rcl names the logger
  const ros2::NodeParameters o =
      parse({"--ros-args", "-p", "model:=m", "-p", "pose:=odom:wheel_odom", "-r", "__ns:=/robot1"});
  EXPECT_EQ(ros2::resolveTopic(o.pose.name, o), "/robot1/wheel_odom");
  for (const char* bad : {"ros_distro:=ardent", "ros_distro:=Humble", "pose:=gps:/fix",
                          "pose:=odom:", "pose:=tf:/", "pose:=odom:bad name", "pose:=map"}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(parse({"--ros-args", "-p", "model:=m", "-p", bad}), InputError);
  }
  for (const char* bad : {"__node:=2lidar", "__node:=front-lidar", "__node:=", "__ns:=/robot/",
                          "__ns:=/robot//one", "__ns:=/9robot"}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(parse({"--ros-args", "-p", "model:=m", "-r", bad}), InputError);
  }
}

TEST(Ros2NodeArguments, DomainIdFromTheEnvironment) {
  unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(ros2::domainIdFromEnvironment(), 0);
  setenv("ROS_DOMAIN_ID", "42", 1);
  EXPECT_EQ(ros2::domainIdFromEnvironment(), 42);
  setenv("ROS_DOMAIN_ID", "300", 1);
  EXPECT_THROW(ros2::domainIdFromEnvironment(), InputError);
  unsetenv("ROS_DOMAIN_ID");
}

TEST(Ros2NodeArguments, TheWatchModesParametersMapOntoTheWatchersSettings) {
  const ros2::NodeParameters d = parse({"--ros-args", "-p", "model:=m"});
  EXPECT_EQ(d.mode, ros2::NodeMode::apply);
  EXPECT_EQ(d.diagnostics_period_s, 1.0);
  EXPECT_EQ(ros2::resolveTopic(d.candidate_topic, d), "/lidarcal/candidate_model");
  EXPECT_FALSE(d.candidate_file.has_value());
  // Unset parameters leave the watcher's defaults.
  const watch::WatchSettings w0 = ros2::watchSettingsFor(d), def = watch::defaultWatchSettings();
  EXPECT_EQ(w0.mode, watch::Mode::watch);
  EXPECT_EQ(w0.false_alarms.per_unit, def.false_alarms.per_unit);
  EXPECT_EQ(w0.false_alarms.unit, watch::Exposure::distance);
  EXPECT_EQ(w0.check.every_m, def.check.every_m);
  EXPECT_EQ(w0.check.bias_replicas, def.check.bias_replicas);
  EXPECT_FALSE(w0.check.landmark_radius_m.has_value());
  EXPECT_EQ(w0.association.drift_per_m, def.association.drift_per_m);
  TempDir dir;
  const std::string file = "candidate_file:=" + (dir / "candidate.json").string();
  const ros2::NodeParameters p =
      parse({"--ros-args", "-p", "mode:=learn", "-p", "false_alarms:=0.02", "-p",
             "false_alarms_per:=hour", "-p", "check_every:=5.5", "-p", "check_bias_replicas:=2",
             "-p", "landmark_radius:=0.04", "-p", "candidate_topic:=/fleet/candidate", "-p",
             file.c_str(), "-p", "diagnostics_period:=0.5"});
  EXPECT_TRUE(p.model_file.empty());  // learn mode may start without a model
  EXPECT_EQ(p.candidate_topic, "/fleet/candidate");
  EXPECT_EQ(*p.candidate_file, (dir / "candidate.json").string());
  EXPECT_EQ(p.diagnostics_period_s, 0.5);
  const watch::WatchSettings w = ros2::watchSettingsFor(p);
  EXPECT_EQ(w.mode, watch::Mode::learn);
  EXPECT_EQ(w.false_alarms.per_unit, 0.02);
  EXPECT_EQ(w.false_alarms.unit, watch::Exposure::time);
  EXPECT_EQ(w.check.every_m, 5.5);
  EXPECT_EQ(w.check.bias_replicas, 2);
  EXPECT_EQ(w.check.landmark_radius_m.value_or(0), 0.04);  // the checks' radius and the detector's
  EXPECT_EQ(w.detection.landmark_radius_m.value_or(0), 0.04);
  EXPECT_NO_THROW(w.validate());
  for (const char* bad :
       {"mode:=observe", "false_alarms:=0", "false_alarms:=-1", "false_alarms:=abc",
        "false_alarms:=nan", "false_alarms_per:=day", "check_every:=0", "check_bias_replicas:=-1",
        "check_bias_replicas:=2.5", "check_bias_replicas:=101", "landmark_radius:=-0.1",
        "diagnostics_period:=0", "candidate_topic:=bad name",
        "candidate_file:=/no/such/dir/m.json"}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(parse({"--ros-args", "-p", "model:=m", "-p", bad}), InputError);
  }
  // Empty values (a launch file's defaults) leave them unset.
  const ros2::NodeParameters e = parse(
      {"--ros-args", "-p", "model:=m", "-p", "landmark_radius:=", "-p", "candidate_file:=''"});
  EXPECT_FALSE(e.landmark_radius_m.has_value());
  EXPECT_FALSE(e.candidate_file.has_value());
  EXPECT_THROW(parse({"--ros-args", "-p", "mode:=watch"}), InputError);  // watch needs a model
  EXPECT_THROW(parse({"--ros-args", "-p", "mode:=learn", "-p",
                      ("candidate_file:=" + dir.path().string()).c_str()}),
               InputError);  // a directory
}

/// A 100-beam scan whose ranges cover 0.2-11.1 m.
std::vector<float> ranges(float offset = 0.0f) {
  std::vector<float> r;
  for (int i = 0; i < 100; ++i) r.push_back(0.2f + 0.11f * static_cast<float>(i) + offset);
  r[1] = std::numeric_limits<float>::infinity();
  r[2] = std::numeric_limits<float>::quiet_NaN();
  return r;
}

ros2::ScanFields fields(std::vector<float>& r, std::size_t intensities = 0) {
  ros2::ScanFields f;
  f.angle_min = -3.1f;
  f.angle_increment = 0.06f;
  f.angle_max = f.angle_min + 99 * f.angle_increment;
  f.range_min = 0.15f;
  f.range_max = 12.0f;
  f.ranges = r.data();
  f.beams = r.size();
  f.intensities = intensities;
  return f;
}

ros2::LiveSettings settings() {
  ros2::LiveSettings s;
  s.model_file = "model.json";
  s.topic = "/scan";
  return s;
}

struct LiveCase {
  CalibrationModel model = polynomialModel("", 100);
  calibration::ReadingCorrector correct = calibration::readingCorrector(
      model, calibration::InversionMethod::ls, calibration::kDefaultOutside);
  ros2::LiveCorrector live{model, settings(), correct};
};

TEST(Ros2LiveCorrector, CorrectsExactlyAsCorrectLaserRanges) {
  LiveCase c;
  for (float offset : {0.0f, 0.013f, 0.0f}) {  // the third scan's readings are remembered ones
    std::vector<float> r = ranges(offset), expected = r;
    pipeline::MemoCorrector memo(c.correct);
    pipeline::CorrectionStats stats;
    pipeline::correctLaserRanges(expected, 0.15, 12.0, memo, stats);
    ros2::ScanFields f = fields(r, 100);
    ASSERT_EQ(c.live.process(f), ros2::ScanVerdict::publish);
    for (std::size_t i = 0; i < r.size(); ++i)
      EXPECT_TRUE(std::memcmp(&r[i], &expected[i], sizeof(float)) == 0)
          << i << ": " << r[i] << " vs " << expected[i];
  }
  EXPECT_EQ(c.live.stats().correction.scans, 3u);
}

TEST(Ros2LiveCorrector, MalformedScansAreDroppedUntouchedAndCounted) {
  LiveCase c;
  std::vector<float> good = ranges();
  ros2::ScanFields first = fields(good);
  ASSERT_EQ(c.live.process(first), ros2::ScanVerdict::publish);
  std::vector<float> r = ranges(), longer = ranges();
  longer.push_back(3.0f);
  const std::vector<float> untouched = r;
  std::vector<ros2::ScanFields> bad(6, fields(r));
  bad[0].beams = 0;
  bad[1] = fields(longer);
  bad[2].angle_increment = std::numeric_limits<float>::quiet_NaN();
  bad[3].range_max = -std::numeric_limits<float>::infinity();
  bad[4].range_min = 13.0f;
  bad[5].intensities = 7;
  const ros2::DropReason reasons[] = {ros2::DropReason::empty,
                                      ros2::DropReason::beam_count,
                                      ros2::DropReason::non_finite_field,
                                      ros2::DropReason::non_finite_field,
                                      ros2::DropReason::range_limits,
                                      ros2::DropReason::intensities};
  for (std::size_t k = 0; k < bad.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(c.live.process(bad[k]), ros2::ScanVerdict::drop);
    EXPECT_EQ(c.live.dropReason(), reasons[k]);
    EXPECT_FALSE(c.live.message().empty());
  }
  // nothing corrected
  EXPECT_EQ(std::memcmp(r.data(), untouched.data(), r.size() * sizeof(float)), 0);
  EXPECT_EQ(c.live.stats().droppedTotal(), 6u);
  EXPECT_EQ(c.live.stats().correction.scans, 1u);
}

TEST(Ros2LiveCorrector, TheFirstScanOfAnotherSensorIsRefused) {
  CalibrationModel m = polynomialModel("", 360);
  const auto correct = calibration::readingCorrector(m, calibration::InversionMethod::ls,
                                                     calibration::kDefaultOutside);
  ros2::LiveCorrector live(m, settings(), correct);
  std::vector<float> r = ranges();
  ros2::ScanFields f = fields(r);
  EXPECT_EQ(live.process(f), ros2::ScanVerdict::refuse);
  EXPECT_NE(live.message().find("360"), std::string::npos) << live.message();
  // Other range limits: refused without force, a warning with it.
  ros2::LiveCorrector strict(polynomialModel("", 100), settings(), correct);
  f.range_max = 30.0f;
  EXPECT_EQ(strict.process(f), ros2::ScanVerdict::refuse);
  ros2::LiveSettings forced = settings();
  forced.force = true;
  ros2::LiveCorrector lenient(polynomialModel("", 100), forced, correct);
  EXPECT_EQ(lenient.process(f), ros2::ScanVerdict::publish);
  EXPECT_FALSE(lenient.sensorWarning().empty());
}

TEST(Ros2LiveCorrector, WithoutAModelScansPassUncorrectedUntilOneIsLearnt) {
  ros2::LiveCorrector live(settings());
  EXPECT_FALSE(live.hasModel());
  std::vector<float> r = ranges();
  const std::vector<float> received = r;
  ros2::ScanFields f = fields(r);
  ASSERT_EQ(live.process(f), ros2::ScanVerdict::publish);
  EXPECT_EQ(std::memcmp(r.data(), received.data(), r.size() * sizeof(float)), 0);
  std::vector<float> longer = ranges();
  longer.push_back(3.0f);
  ros2::ScanFields other = fields(longer);  // the first scan set the sensor's beam count
  EXPECT_EQ(live.process(other), ros2::ScanVerdict::drop);
  EXPECT_EQ(live.dropReason(), ros2::DropReason::beam_count);
  // A model learnt: from the next scan on, corrected as `correct` corrects.
  LiveCase c;
  live.useModel(c.model, c.correct);
  EXPECT_TRUE(live.hasModel());
  std::vector<float> next = ranges(0.013f), expected = next;
  pipeline::MemoCorrector memo(c.correct);
  pipeline::CorrectionStats stats;
  pipeline::correctLaserRanges(expected, 0.15, 12.0, memo, stats);
  ros2::ScanFields g = fields(next);
  ASSERT_EQ(live.process(g), ros2::ScanVerdict::publish);
  EXPECT_EQ(std::memcmp(next.data(), expected.data(), next.size() * sizeof(float)), 0);
  EXPECT_EQ(live.stats().uncorrected, 1u);
  EXPECT_EQ(live.stats().correction.scans, 1u);
  EXPECT_EQ(live.stats().droppedTotal(), 1u);
}

TEST(Ros2WarningLimiter, OnePerPeriodAndTheHeldBackOnesCounted) {
  ros2::WarningLimiter w(5.0);
  EXPECT_EQ(w.offer("empty", "dropped", 0.0), "dropped");
  EXPECT_EQ(w.offer("empty", "dropped", 1.0), "");
  EXPECT_EQ(w.offer("empty", "dropped", 4.9), "");
  EXPECT_EQ(w.offer("beams", "other", 4.9), "other");  // kinds are limited apart
  EXPECT_EQ(w.offer("empty", "dropped", 5.0), "dropped (2 more like it since the last warning)");
  EXPECT_EQ(w.offer("empty", "dropped", 10.0), "dropped");
}

TEST(ExportedModelYaml, CorrectsEveryReadingAsTheModelItWasExportedFrom) {
  TempDir dir;
  const CalibrationModel m = polynomialModel("RPLIDAR A2", 360);
  for (const auto inversion :
       {calibration::InversionMethod::ls, calibration::InversionMethod::ml}) {
    pipeline::ExportConfig config;
    config.inversion = inversion;
    config.outside = calibration::Outside::drop;
    config.source = "model.json";
    writeFile(dir / "model.yaml", pipeline::exportYaml(m, config));
    ASSERT_TRUE(io::isExportedModelYaml(dir / "model.yaml"));
    const io::ExportedModel e = io::readExportedModelYaml(dir / "model.yaml");
    EXPECT_EQ(e.inversion, calibration::toString(inversion));
    EXPECT_EQ(e.outside, calibration::toString(calibration::Outside::drop));
    EXPECT_EQ(e.model.sensor_name, "RPLIDAR A2");
    EXPECT_EQ(e.model.beams.value_or(0), 360);
    const auto a = calibration::readingCorrector(m, inversion, calibration::Outside::drop);
    const auto b = calibration::readingCorrector(e.model, inversion, calibration::Outside::drop);
    for (double y = 0.15; y < 12.0; y += 0.0037) {
      const auto ca = a(y), cb = b(y);
      EXPECT_EQ(ca.fate, cb.fate) << y;
      EXPECT_TRUE(ca.range_m == cb.range_m || (std::isnan(ca.range_m) && std::isnan(cb.range_m)))
          << y;
    }
  }
  io::writeModel(dir / "model.json", m);
  EXPECT_FALSE(io::isExportedModelYaml(dir / "model.json"));
  writeFile(dir / "broken.yaml", "format: \"lidarcal-ros-params/1\"\nsensor_name: \"x\"\n");
  EXPECT_THROW(io::readExportedModelYaml(dir / "broken.yaml"), InputError);
}

}  // namespace
}  // namespace lidarcal::test
