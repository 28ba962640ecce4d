// SPDX-License-Identifier: BSD-3-Clause
// The per-scan path of lidarcal_node (ros1::ScanPath::process, what its scan callback does apart
// from the transport: the copy of the message's ranges, the raw readings handed to the watcher
// with their pose, the correction) in apply, watch and learn modes side by side in one run. The
// scans are a simulated drive (data/scenes/driving_large_poles.json: 360 beams, 10 Hz, readings
// quantised to 1 mm as sensors report them, the odometry's poses) with 20 mm added from scan 900,
// so that while the scans are corrected the watcher's checks run, it raises an alarm and, in learn
// mode, refits and switches to a new model. The watcher's detection and fits run on threads of
// their own meanwhile (on 2 shared cores they compete with the correction for the CPU). Each scan
// is timed alone (wall and the correcting thread's CPU time); between two scans, untimed, the
// bench waits while the watcher is more than 4 scans behind, so that it watches every scan as a
// robot at 10 Hz would have it. The first 300 scans warm the correction up (it remembers each
// distinct reading) and build the watcher's baseline; the next 1200 are timed.
//
//   build/bench/bench_node_watch
// Time: mean wall time per scan; counters: cpu_us and cpu_max_us (CPU time of the correcting
// thread), p99_us and max_us (wall), and what the watcher did during the timed scans. (The CPU
// column counts the untimed waits as well.) Measured (Release, 2 shared cores under load 7,
// medians of 3): wall 14 / 20 / 25 us per scan in apply / watch / learn mode, CPU 7 / 19 / 17 us,
// 99th percentile 16 / 65 / 63 us; the largest CPU time 74 / 76 / 97 us, the switch included.

#include <benchmark/benchmark.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

#include "io/raw_scan_cloud.hpp"
#include "io/scene_io.hpp"
#include "ros/scan_path.hpp"
#include "simulation/simulator.hpp"
#include "watch/range_change.hpp"

namespace {

using namespace lidarcal;

constexpr std::size_t kWarmScans = 300, kTimedScans = 1200;

/// The drive: each scan's readings, pose and stamp, and the scene's sensor as the model.
struct Drive {
  Scene scene;
  std::vector<io::RawScan> scans;
  std::shared_ptr<const CalibrationModel> model;
};

Drive simulateDrive() {
  Drive d;
  d.scene =
      io::readScene(std::string(LIDARCAL_SOURCE_DIR) + "/data/scenes/driving_large_poles.json");
  d.scene.path.stops = static_cast<int>(kWarmScans + kTimedScans);
  const auto stops = simulation::planStops(d.scene, 1);
  const watch::RangeChange change = watch::parseRangeChange("20@900");
  for (std::size_t i = 0; i < stops.size(); ++i) {
    io::RawScan raw =
        io::toRawScan(simulation::simulateScan(d.scene, stops[i], i, 1).scan,
                      d.scene.sensor.range.range_min_m, d.scene.sensor.range.range_max_m);
    raw.stamp_s = 100.0 + 0.1 * static_cast<double>(i);
    watch::applyChange(change, i, raw);
    for (float& r : raw.ranges_m) r = std::round(r * 1000.0f) / 1000.0f;
    d.scans.push_back(std::move(raw));
  }
  auto m = std::make_shared<CalibrationModel>();
  m->model = d.scene.sensor.range;
  m->alpha_covariance.assign(m->model.bias.alpha.size() * m->model.bias.alpha.size(), 0.0);
  m->fitted_range_m = std::make_pair(m->model.range_min_m, m->model.range_max_m);
  d.model = m;
  return d;
}

const Drive& drive() {
  static const Drive d = simulateDrive();
  return d;
}

/// Scan i as the node's callback sees it: the received message's fields (`received` its ranges).
io::LaserScanView messageOf(const Drive& d, std::size_t i, const std::vector<float>& received) {
  io::LaserScanView v;
  const double stamp = d.scans[i].stamp_s;
  v.stamp_sec = static_cast<std::int64_t>(stamp);
  v.stamp_nanosec = static_cast<std::uint32_t>(std::lround(1e9 * (stamp - std::floor(stamp))));
  v.angle_min = static_cast<float>(d.scene.sensor.angle_min_rad);
  v.angle_increment = static_cast<float>(d.scene.sensor.angle_increment_rad);
  v.range_min = static_cast<float>(d.scene.sensor.range.range_min_m);
  v.range_max = static_cast<float>(d.scene.sensor.range.range_max_m);
  v.ranges = received.data();
  v.count = received.size();
  return v;
}

/// Scan i's odometry, as the node's pose callback hands it on.
void addOdometry(ros1::ScanPath& path, const Drive& d, std::size_t i) {
  if (!path.poses() || i >= d.scans.size()) return;
  ros2::ReceivedTransform t;
  t.stamp = ros2::rosTimeFromSeconds(d.scans[i].stamp_s);
  t.parent = "odom";
  t.child = "laser";
  t.x = d.scans[i].pose.x_m;
  t.y = d.scans[i].pose.y_m;
  t.qz = std::sin(0.5 * d.scans[i].pose.yaw_rad);
  t.qw = std::cos(0.5 * d.scans[i].pose.yaw_rad);
  path.poses()->addOdometry(t);
}

/// Waits (untimed) while the watcher is more than 4 scans behind the correction.
void keepPace(const ros1::ScanPath& path, std::size_t processed) {
  if (const watch::LiveWatcher* w = path.watcher())
    while (w->state().scans + w->dropped() + 4 < processed)
      std::this_thread::sleep_for(std::chrono::microseconds(200));
}

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Scan i through the path: the node copies the received message, then corrects the copy.
ros1::ScanOutcome processScan(ros1::ScanPath& path, const Drive& d, std::size_t i) {
  const std::vector<float>& received = d.scans[i].ranges_m;
  std::vector<float> ranges = received;
  ros1::ScanOutcome out = path.process(messageOf(d, i, received), "laser", ranges);
  benchmark::DoNotOptimize(ranges.data());
  return out;
}

void NodeScanPath(benchmark::State& state, std::optional<watch::Mode> mode) {
  const Drive& d = drive();
  ros1::ScanPathSettings s;
  s.model_file = "model.json";
  if (mode) {
    s.watch = watch::defaultWatchSettings();
    s.watch->mode = *mode;
    s.watch->check.landmark_radius_m = d.scene.landmarks.front().radius_m;
    s.watch->detection.landmark_radius_m = s.watch->check.landmark_radius_m;
  }
  ros1::ScanPath path(s, d.model);
  addOdometry(path, d, 0);
  std::size_t i = 0;
  for (; i < kWarmScans; ++i) {
    addOdometry(path, d, i + 1);  // odometry arrives ahead of the scans (its own callback)
    processScan(path, d, i);
    keepPace(path, i + 1);
  }
  const watch::WatchState before = path.watcher() ? path.watcher()->state() : watch::WatchState{};
  std::vector<double> wall_us, cpu_us;
  for (auto _ : state) {
    addOdometry(path, d, i + 1);
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = threadCpuSeconds();
    processScan(path, d, i);
    cpu_us.push_back(1e6 * (threadCpuSeconds() - cpu_start));
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(wall);
    wall_us.push_back(1e6 * wall);
    keepPace(path, ++i);
  }
  std::sort(wall_us.begin(), wall_us.end());
  double cpu_sum = 0.0;
  for (double c : cpu_us) cpu_sum += c;
  state.counters["cpu_us"] = cpu_sum / static_cast<double>(cpu_us.size());
  state.counters["cpu_max_us"] = *std::max_element(cpu_us.begin(), cpu_us.end());
  state.counters["p99_us"] = wall_us[wall_us.size() * 99 / 100];
  state.counters["max_us"] = wall_us.back();
  if (const watch::LiveWatcher* w = path.watcher()) {
    const watch::WatchState after = w->state();
    state.counters["checks"] = static_cast<double>(after.checks - before.checks);
    state.counters["alarms"] = static_cast<double>(after.alarms - before.alarms);
    state.counters["switches"] = static_cast<double>(after.switches - before.switches);
    state.counters["not_watched"] = static_cast<double>(w->dropped());
  }
}

}  // namespace

BENCHMARK_CAPTURE(NodeScanPath, Apply, std::optional<watch::Mode>())
    ->Iterations(kTimedScans)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(NodeScanPath, Watch, std::optional<watch::Mode>(watch::Mode::watch))
    ->Iterations(kTimedScans)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(NodeScanPath, Learn, std::optional<watch::Mode>(watch::Mode::learn))
    ->Iterations(kTimedScans)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
