// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Simulated drives for the watcher's tests: a scene of data/scenes/ driven for a number of scans,
// each scan as a recording gives it (polar readings, the odometry's pose, a stamp at 10 Hz), with
// a change of the sensor injected when asked, and the scene's own sensor as a model (standard
// errors zero: the truth the tests control).

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "common/calibration_model.hpp"
#include "io/raw_scan_cloud.hpp"
#include "io/scene_io.hpp"
#include "simulation/simulator.hpp"
#include "simulation/truth_model.hpp"
#include "test_util.hpp"
#include "watch/engine.hpp"
#include "watch/range_change.hpp"

namespace lidarcal::test {

inline Scene drivingScene(const std::string& name, std::size_t scans) {
  Scene scene = io::readScene(sourceDir() / "data" / "scenes" / (name + ".json"));
  scene.path.stops = static_cast<int>(scans);
  return scene;
}

/// The scene's sensor as a calibrated model with zero standard errors, fitted (as a
/// calibration of the drive would be) over the distances from its path to the poles' surfaces.
inline std::shared_ptr<const CalibrationModel> trueModel(const Scene& scene) {
  return std::make_shared<const CalibrationModel>(simulation::truthModel(scene));
}

/// Watcher settings for a scene: its pole radius given, as a user who measured it would.
inline watch::WatchSettings watchSettings(const Scene& scene, watch::Mode mode) {
  watch::WatchSettings s = watch::defaultWatchSettings();
  s.mode = mode;
  s.check.landmark_radius_m = scene.landmarks.front().radius_m;
  s.detection.landmark_radius_m = s.check.landmark_radius_m;
  return s;
}

/// Scan i of the drive of `seed`, as a recording gives it, with `change` applied.
inline io::RawScan driveScan(const Scene& scene, const std::vector<TruthStop>& stops, std::size_t i,
                             std::uint64_t seed, const watch::RangeChange& change = {}) {
  const auto sim = simulation::simulateScan(scene, stops[i], i, seed);
  io::RawScan raw =
      io::toRawScan(sim.scan, scene.sensor.range.range_min_m, scene.sensor.range.range_max_m);
  raw.stamp_s = 0.1 * static_cast<double>(i);
  watch::applyChange(change, i, raw);
  return raw;
}

/// Drives every scan of a scene through an engine (its sink sees the checks).
inline void driveThrough(watch::Engine& engine, const Scene& scene, std::uint64_t seed,
                         const watch::RangeChange& change = {}) {
  const auto stops = simulation::planStops(scene, seed);
  for (std::size_t i = 0; i < stops.size(); ++i)
    engine.observe(driveScan(scene, stops, i, seed, change));
  engine.finish();
}

}  // namespace lidarcal::test
