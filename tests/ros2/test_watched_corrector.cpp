// SPDX-License-Identifier: BSD-3-Clause
// The node's scan path in modes watch and learn without DDS (ros2::WatchedCorrector): scans of a
// simulated drive corrected exactly as LiveCorrector corrects them, watched only with a pose,
// passed uncorrected in learn mode until a model is learnt; its /diagnostics entries and the log
// line of a switch, against the models the test builds.

#include <chrono>
#include <cstring>
#include <thread>

#include <gtest/gtest.h>

#include "ros2/watched_corrector.hpp"
#include "watch/diagnostics.hpp"
#include "watch/drive.hpp"

namespace lidarcal::test {
namespace {

/// Scan i of a drive as the node receives it: ranges, angles and limits of a LaserScan.
struct ReceivedScan {
  std::vector<float> ranges;
  ros2::ScanFields fields;
  ReceivedScan(const Scene& scene, const io::RawScan& raw) : ranges(raw.ranges_m) {
    const SensorSpec& s = scene.sensor;
    fields.angle_min = static_cast<float>(s.angle_min_rad);
    fields.angle_increment = static_cast<float>(s.angle_increment_rad);
    fields.angle_max = fields.angle_min + fields.angle_increment * static_cast<float>(s.beams - 1);
    fields.range_min = static_cast<float>(s.range.range_min_m);
    fields.range_max = static_cast<float>(s.range.range_max_m);
    fields.ranges = ranges.data();
    fields.beams = ranges.size();
  }
};

ros2::LiveSettings liveSettings() {
  ros2::LiveSettings s;
  s.model_file = "model.json";
  s.topic = "/scan";
  return s;
}

/// Waits (bounded) until the watcher has taken `scans` scans.
bool watcherReaches(const ros2::WatchedCorrector& w, std::size_t scans) {
  for (int k = 0; k < 2000; ++k) {
    if (w.watcher().state().scans >= scans) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

TEST(WatchedCorrector, CorrectsAsLiveCorrectorAndWatchesOnlyScansWithAPose) {
  const Scene scene = drivingScene("driving_large_poles", 4);
  const auto stops = simulation::planStops(scene, 7);
  const auto model = trueModel(scene);
  ros2::WatchedCorrector w(watchSettings(scene, watch::Mode::watch), model, liveSettings());
  ros2::LiveCorrector reference(
      *model, liveSettings(),
      calibration::readingCorrector(*model, calibration::InversionMethod::ls,
                                    calibration::kDefaultOutside));
  ros2::PoseLookup none;
  none.why = "no odometry message on /odom yet";
  for (std::size_t i = 0; i < stops.size(); ++i) {
    SCOPED_TRACE(i);
    const io::RawScan raw = driveScan(scene, stops, i, 7);
    ReceivedScan got(scene, raw), expected(scene, raw);
    ros2::PoseLookup pose = none;
    if (i >= 2) pose.pose = raw.pose;  // the first two scans come before any odometry
    ASSERT_EQ(w.process(got.fields, {1700000000, 0}, pose), ros2::ScanVerdict::publish);
    ASSERT_EQ(reference.process(expected.fields), ros2::ScanVerdict::publish);
    EXPECT_EQ(std::memcmp(got.ranges.data(), expected.ranges.data(), got.ranges.size() * 4), 0);
    EXPECT_EQ(w.notWatched().empty(), i >= 2) << w.notWatched();
  }
  EXPECT_EQ(w.withoutPose(), 2u);
  ASSERT_TRUE(watcherReaches(w, 2));
  EXPECT_EQ(w.watcher().state().scans, 2u);  // the two with a pose, no more
  EXPECT_EQ(w.correctingVersion(), 1u);
  const ros2::DiagnosticEntry e = ros2::watchDiagnostics(w, "/scan", "sim_lidar");
  EXPECT_EQ(e.name, "lidarcal: range model of /scan");
  EXPECT_EQ(e.hardware_id, "sim_lidar");
  EXPECT_EQ(e.level, ros2::DiagnosticLevel::warn);  // no check yet
  std::map<std::string, std::string> values(e.values.begin(), e.values.end());
  EXPECT_EQ(values["mode"], "watch");
  EXPECT_EQ(values["scans without a pose"], "2");
  EXPECT_EQ(values["scans not watched"], "2");
  EXPECT_EQ(values["scans corrected"], "4");
}

TEST(WatchedCorrector, LearnModeWithoutAModelPassesScansUncorrectedAndSaysSo) {
  const Scene scene = drivingScene("driving_large_poles", 2);
  const auto stops = simulation::planStops(scene, 8);
  ros2::WatchedCorrector w(watchSettings(scene, watch::Mode::learn), nullptr, liveSettings());
  const io::RawScan raw = driveScan(scene, stops, 0, 8);
  ReceivedScan got(scene, raw);
  ros2::PoseLookup pose;
  pose.pose = raw.pose;
  ASSERT_EQ(w.process(got.fields, {1700000000, 0}, pose), ros2::ScanVerdict::publish);
  EXPECT_EQ(std::memcmp(got.ranges.data(), raw.ranges_m.data(), got.ranges.size() * 4), 0);
  EXPECT_EQ(w.correctingVersion(), 0u);
  const ros2::DiagnosticEntry e = ros2::watchDiagnostics(w, "/scan", "");
  EXPECT_EQ(e.level, ros2::DiagnosticLevel::warn);
  EXPECT_NE(e.message.find("learning"), std::string::npos) << e.message;
  std::map<std::string, std::string> values(e.values.begin(), e.values.end());
  EXPECT_EQ(values["scans passed uncorrected"], "1");
  EXPECT_EQ(values["model version"], "0");
}

TEST(WatchedCorrector, ApplyModesEntryIsOkAndNamesTheModel) {
  const Scene scene = drivingScene("driving_large_poles", 2);
  const auto model = trueModel(scene);
  ros2::LiveCorrector live(*model, liveSettings(),
                           calibration::readingCorrector(*model, calibration::InversionMethod::ls,
                                                         calibration::kDefaultOutside));
  const ros2::DiagnosticEntry e =
      ros2::applyDiagnostics(live, *model, "model.json", "/scan", "sim_lidar");
  EXPECT_EQ(e.level, ros2::DiagnosticLevel::ok);
  EXPECT_NE(e.message.find("model.json"), std::string::npos);
  std::map<std::string, std::string> values(e.values.begin(), e.values.end());
  EXPECT_EQ(values["mode"], "apply");
  // The scene's bias at 2 m, in mm, as the entry states it.
  char at2[32];
  std::snprintf(at2, sizeof at2, "%+.1f", 1000.0 * (scene.sensor.range.bias(2.0) - 2.0));
  EXPECT_EQ(values["bias at 2 m"].rfind(at2, 0), 0u) << values["bias at 2 m"];
}

TEST(WatchedCorrector, TheSwitchLineStatesBothModelsAndWhy) {
  const Scene scene = drivingScene("driving_large_poles", 2);
  auto longer = std::make_shared<CalibrationModel>(*trueModel(scene));
  longer->model.bias.alpha[0] += 0.020;  // the sensor reads 20 mm longer
  watch::RefitEvent e;
  e.candidate = longer;
  e.previous = trueModel(scene);
  e.model_version = 2;
  e.decided_at = 1087;
  e.stretch = {901, 1029, 31.0, 3.8, 102.9};
  e.decision.adopt = true;
  e.decision.reason = "the candidate differs";
  const std::string line = ros2::switchLine(e);
  EXPECT_EQ(line.rfind("switched to model 2 at scan 1087", 0), 0u) << line;
  for (double d : {1.0, 2.0, 3.0}) {
    char now[32], was[32];
    std::snprintf(now, sizeof now, "%+.1f", 1000.0 * (scene.sensor.range.bias(d) + 0.020 - d));
    std::snprintf(was, sizeof was, "(was %+.1f", 1000.0 * (scene.sensor.range.bias(d) - d));
    EXPECT_NE(line.find(now), std::string::npos) << d << ": " << line;
    EXPECT_NE(line.find(was), std::string::npos) << d << ": " << line;
  }
  EXPECT_NE(line.find("scans 901-1029"), std::string::npos) << line;
  EXPECT_NE(line.find("the candidate differs"), std::string::npos) << line;
  const std::string c = ros2::candidateLine(e, "published on /c");
  EXPECT_NE(c.find("candidate adopted (the candidate differs); published on /c"), std::string::npos)
      << c;
}

}  // namespace
}  // namespace lidarcal::test
