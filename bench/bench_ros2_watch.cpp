// SPDX-License-Identifier: BSD-3-Clause
// The ROS 2 node's per-scan correction path in its three modes, side by side in one run, on a
// simulated drive (data/scenes/driving_large_poles.json: 360 beams, readings in whole
// millimetres, a scan every 3 cm at 10 Hz) with a 20 mm offset from scan 500 on, so that the
// watcher's checks raise alarms and, in learn mode, its refits run and it switches models:
//
// - `Ros2Apply`: ros2::LiveCorrector::process on the received sample (mode apply);
// - `Ros2Watch`, `Ros2Learn`: what lidarcal_ros2_node does per scan in modes watch and learn
//   (ros2::WatchedCorrector::process): the scan's odometry taken into ros2::LivePoses, the scan
//   frame's pose looked up at its stamp, the raw readings copied, the ranges corrected with the
//   watcher's model in use (following a switch), the copy offered to the watcher;
// - `Ros2WatchWithoutFits`: the same in mode watch with the checks spaced beyond the drive, so
//   that the watcher detects and tracks but never fits: the path's own cost beside
//   `Ros2Apply`, and the fits' effect on it beside `Ros2Watch`.
//
// Each iteration is one scan of the drive, in order (1500 scans), timed alone (manual time; the
// sample's copy into the buffer the corrector works on is not timed). Between scans the bench
// waits, untimed, while the watcher is more than 24 scans behind (its queue holds 64), as a 10 Hz
// sensor would leave it time: every scan is watched, and the watcher's detection and fits run on
// their own threads while the correction is timed. Counters: the per-scan time's median, 99th
// percentile and maximum (us), and the watcher's checks, alarms and switches over the run.
//
//   build/bench/bench_ros2_watch        (Time = mean per scan)

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <thread>
#include <vector>

#include "io/raw_scan_cloud.hpp"
#include "io/scene_io.hpp"
#include "ros2/live_poses.hpp"
#include "ros2/watched_corrector.hpp"
#include "simulation/simulator.hpp"
#include "simulation/truth_model.hpp"
#include "watch/range_change.hpp"

namespace {

using namespace lidarcal;
using Clock = std::chrono::steady_clock;

constexpr std::size_t kScans = 1500;
constexpr std::size_t kLeadScans = 24;

/// The drive as the node receives it: each scan's ranges (the change applied) and pose.
struct Drive {
  Scene scene;
  std::shared_ptr<const CalibrationModel> model;
  std::vector<std::vector<float>> ranges;
  std::vector<Pose2> poses;
};

const Drive& drive() {
  static const Drive d = [] {
    Drive out;
    out.scene =
        io::readScene(std::string(LIDARCAL_SOURCE_DIR) + "/data/scenes/driving_large_poles.json");
    out.scene.path.stops = static_cast<int>(kScans);
    out.model = std::make_shared<const CalibrationModel>(simulation::truthModel(out.scene));
    const auto stops = simulation::planStops(out.scene, 1);
    const watch::RangeChange change = watch::parseRangeChange("20@500");
    const RangeModel& r = out.scene.sensor.range;
    for (std::size_t i = 0; i < stops.size(); ++i) {
      io::RawScan raw = io::toRawScan(simulation::simulateScan(out.scene, stops[i], i, 1).scan,
                                      r.range_min_m, r.range_max_m);
      watch::applyChange(change, i, raw);
      for (float& x : raw.ranges_m)  // whole millimetres, as the sensors report them
        x = static_cast<float>(std::round(static_cast<double>(x) * 1000.0) / 1000.0);
      out.ranges.push_back(raw.ranges_m);
      out.poses.push_back(raw.pose);
    }
    return out;
  }();
  return d;
}

ros2::RosTime stampOf(std::size_t i) {
  return {1700000000 + static_cast<std::int32_t>(i / 10),
          static_cast<std::uint32_t>(i % 10) * 100000000u};
}

ros2::ScanFields fieldsOf(const Scene& scene, std::vector<float>& sample) {
  ros2::ScanFields f;
  f.angle_min = static_cast<float>(scene.sensor.angle_min_rad);
  f.angle_increment = static_cast<float>(scene.sensor.angle_increment_rad);
  f.angle_max = f.angle_min + f.angle_increment * static_cast<float>(sample.size() - 1);
  f.range_min = static_cast<float>(scene.sensor.range.range_min_m);
  f.range_max = static_cast<float>(scene.sensor.range.range_max_m);
  f.ranges = sample.data();
  f.beams = sample.size();
  return f;
}

ros2::LiveSettings liveSettings() {
  ros2::LiveSettings s;
  s.model_file = "model.json";
  s.topic = "/scan";
  return s;
}

/// Median, 99th percentile and maximum of the per-scan times, as counters in microseconds.
void latencyCounters(benchmark::State& state, std::vector<double> seconds) {
  std::sort(seconds.begin(), seconds.end());
  auto at = [&](double q) {
    return 1e6 *
           seconds[std::min(seconds.size() - 1,
                            static_cast<std::size_t>(q * static_cast<double>(seconds.size())))];
  };
  state.counters["p50_us"] = at(0.5);
  state.counters["p99_us"] = at(0.99);
  state.counters["max_us"] = 1e6 * seconds.back();
}

void Ros2Apply(benchmark::State& state) {
  const Drive& d = drive();
  const auto correct = pipeline::modelCorrector(*d.model, calibration::InversionMethod::ls,
                                                calibration::kDefaultOutside, "model.json");
  ros2::LiveCorrector live(*d.model, liveSettings(), correct);
  std::vector<float> sample;
  std::vector<double> seconds;
  std::size_t i = 0;
  for (auto _ : state) {
    sample = d.ranges[i++ % d.ranges.size()];  // the sample as Cyclone hands it over
    ros2::ScanFields f = fieldsOf(d.scene, sample);
    const auto t0 = Clock::now();
    benchmark::DoNotOptimize(live.process(f));
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    state.SetIterationTime(s);
    seconds.push_back(s);
  }
  latencyCounters(state, seconds);
}

/// `fits`: false sets the checks' spacing beyond the drive, so that no fit ever runs (detection
/// still does): the path's own cost, without fits beside it.
void watchedPath(benchmark::State& state, watch::Mode mode, bool fits = true) {
  const Drive& d = drive();
  watch::WatchSettings settings = watch::defaultWatchSettings();
  settings.mode = mode;
  if (!fits) settings.check.every_m = 1e9;
  settings.check.landmark_radius_m = d.scene.landmarks.front().radius_m;
  settings.detection.landmark_radius_m = settings.check.landmark_radius_m;
  ros2::WatchedCorrector w(settings, d.model, liveSettings());
  ros2::LivePoses poses({});
  std::vector<float> sample;
  std::vector<double> seconds;
  std::size_t i = 0;
  for (auto _ : state) {
    while (w.watcher().state().scans + kLeadScans < i)  // untimed: the watcher catches up
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const std::size_t k = i++ % d.ranges.size();
    sample = d.ranges[k];
    ros2::ScanFields f = fieldsOf(d.scene, sample);
    ros2::ReceivedTransform odom;  // the odometry of the scan, as the pose input hands it on
    odom.stamp = stampOf(k);
    odom.parent = "odom";
    odom.child = "laser";
    odom.x = d.poses[k].x_m;
    odom.y = d.poses[k].y_m;
    odom.qz = std::sin(d.poses[k].yaw_rad / 2);
    odom.qw = std::cos(d.poses[k].yaw_rad / 2);
    const auto t0 = Clock::now();
    poses.addOdometry(odom);
    const ros2::PoseLookup pose = poses.at("laser", odom.stamp);
    benchmark::DoNotOptimize(w.process(f, odom.stamp, pose));
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    state.SetIterationTime(s);
    seconds.push_back(s);
  }
  latencyCounters(state, seconds);
  const watch::WatchState s = w.watcher().state();
  state.counters["checks"] = static_cast<double>(s.checks);
  state.counters["alarms"] = static_cast<double>(s.alarms);
  state.counters["switches"] = static_cast<double>(s.switches);
  state.counters["not_watched"] = static_cast<double>(w.watcher().dropped() + w.withoutPose());
}

void Ros2WatchWithoutFits(benchmark::State& state) {
  watchedPath(state, watch::Mode::watch, false);
}
void Ros2Watch(benchmark::State& state) { watchedPath(state, watch::Mode::watch); }
void Ros2Learn(benchmark::State& state) { watchedPath(state, watch::Mode::learn); }

}  // namespace

BENCHMARK(Ros2Apply)->Iterations(kScans)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2WatchWithoutFits)->Iterations(kScans)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2Watch)->Iterations(kScans)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2Learn)->Iterations(kScans)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
