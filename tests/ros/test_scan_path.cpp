// SPDX-License-Identifier: BSD-3-Clause
// lidarcal_node's per-scan path without ROS: watching a scan leaves its correction as apply mode
// makes it, bit for bit; a scan is watched only with a pose at its stamp and never left
// uncorrected for want of one.

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "ros/scan_path.hpp"
#include "watch/drive.hpp"

namespace lidarcal::ros1 {
namespace {

/// Scan i of a simulated drive as a LaserScan's fields (views into `ranges`, its readings).
io::LaserScanView laserScanView(const Scene& scene, const io::RawScan& raw, double stamp_s) {
  io::LaserScanView v;
  v.stamp_sec = static_cast<std::int64_t>(std::floor(stamp_s));
  v.stamp_nanosec = static_cast<std::uint32_t>(std::lround(1e9 * (stamp_s - std::floor(stamp_s))));
  v.angle_min = static_cast<float>(scene.sensor.angle_min_rad);
  v.angle_increment = static_cast<float>(scene.sensor.angle_increment_rad);
  v.range_min = static_cast<float>(raw.range_min_m);
  v.range_max = static_cast<float>(raw.range_max_m);
  v.ranges = raw.ranges_m.data();
  v.count = raw.ranges_m.size();
  return v;
}

/// The odometry's pose of the sensor at `stamp_s`, as lidarcal_node receives it.
ros2::ReceivedTransform odometry(const io::RawScan& raw, double stamp_s) {
  ros2::ReceivedTransform t;
  t.stamp = ros2::rosTimeFromSeconds(stamp_s);
  t.parent = "odom";
  t.child = "laser";
  t.x = raw.pose.x_m;
  t.y = raw.pose.y_m;
  t.qz = std::sin(0.5 * raw.pose.yaw_rad);
  t.qw = std::cos(0.5 * raw.pose.yaw_rad);
  return t;
}

ScanPathSettings settings(const Scene& scene, bool watch) {
  ScanPathSettings s;
  s.model_file = "model.json";
  if (watch) s.watch = test::watchSettings(scene, watch::Mode::watch);
  s.queue_scans = 100;  // every scan of these short drives is watched
  return s;
}

TEST(ScanPath, WatchingLeavesTheCorrectionAsApplyModeMakesIt) {
  const Scene scene = test::drivingScene("driving_large_poles", 60);
  const auto stops = simulation::planStops(scene, 7);
  ScanPath apply(settings(scene, false), test::trueModel(scene));
  ScanPath watching(settings(scene, true), test::trueModel(scene));
  ASSERT_EQ(apply.poses(), nullptr);
  ASSERT_NE(watching.poses(), nullptr);
  std::size_t changed = 0;
  for (std::size_t i = 0; i < stops.size(); ++i) {
    const io::RawScan raw = test::driveScan(scene, stops, i, 7);
    const double stamp = 100.0 + raw.stamp_s;
    ASSERT_FALSE(watching.poses()->addOdometry(odometry(raw, stamp)));
    const io::LaserScanView v = laserScanView(scene, raw, stamp);
    std::vector<float> a = raw.ranges_m, b = raw.ranges_m;
    EXPECT_TRUE(apply.process(v, "laser", a).corrected);
    const ScanOutcome o = watching.process(v, "laser", b);
    EXPECT_TRUE(o.corrected);
    EXPECT_TRUE(o.watched) << o.not_watched;
    for (std::size_t k = 0; k < a.size(); ++k) {
      ASSERT_TRUE((std::isnan(a[k]) && std::isnan(b[k])) || a[k] == b[k]) << i << "/" << k;
      changed += a[k] != raw.ranges_m[k] && std::isfinite(a[k]);
    }
  }
  EXPECT_GT(changed, stops.size() * 50);  // the readings were corrected, not passed on
  EXPECT_EQ(watching.stats().without_pose, 0u);
  EXPECT_EQ(watching.modelVersion(), 1u);  // no switch in watch mode
  EXPECT_EQ(apply.report().level, watch::Health::ok);
}

TEST(ScanPath, AScanWithoutAPoseIsCorrectedButNotWatched) {
  const Scene scene = test::drivingScene("driving_large_poles", 3);
  const auto stops = simulation::planStops(scene, 8);
  ScanPath path(settings(scene, true), test::trueModel(scene));
  const io::RawScan raw = test::driveScan(scene, stops, 0, 8);
  std::vector<float> ranges = raw.ranges_m;
  const ScanOutcome o = path.process(laserScanView(scene, raw, 100.0), "laser", ranges);
  EXPECT_TRUE(o.corrected);
  EXPECT_FALSE(o.watched);
  EXPECT_NE(o.not_watched.find("no odometry"), std::string::npos) << o.not_watched;
  EXPECT_EQ(path.stats().without_pose, 1u);
  // A scan with no beams or a non-finite angle step is passed on, never watched.
  io::LaserScanView bad = laserScanView(scene, raw, 100.1);
  bad.angle_increment = NAN;
  EXPECT_FALSE(path.process(bad, "laser", ranges).watched);
  EXPECT_EQ(path.stats().malformed, 1u);
}

}  // namespace
}  // namespace lidarcal::ros1
