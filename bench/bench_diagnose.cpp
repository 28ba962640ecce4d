// SPDX-License-Identifier: BSD-3-Clause
// Cost of `diagnose` (docs/results/hidden-effects.md): on a 10-stop sequence of the paper field
// (5 poles, 10 scans per stop, landmark level), side by side with the calibration it starts
// from (the joint refinement alone), and on a static room of 150 scans. One core.
//   build/bench/bench_diagnose --benchmark_min_time=1

#include <cmath>

#include <benchmark/benchmark.h>

#include "calibration/calibrate.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/sequence.hpp"
#include "diagnosis/static_scene.hpp"
#include "simulation/simulator.hpp"

namespace {

using namespace lidarcal;

const simulation::LandmarkLevelSample& paperField() {
  static const auto s = [] {
    const auto h = test::hiddenEffectCase("none", 1);
    return simulation::simulateLandmarkLevel(h.config, h.seed);
  }();
  return s;
}

void BM_CalibrateJoint(benchmark::State& state) {
  const auto& s = paperField();
  calibration::CalibrationConfig c;
  for (auto _ : state) benchmark::DoNotOptimize(calibration::calibrate(s.obs, c));
  std::size_t readings = 0;
  for (const auto& sg : s.obs.sightings) readings += sg.beams.size();
  state.counters["readings"] = static_cast<double>(readings);
}

void BM_DiagnoseSequence(benchmark::State& state) {
  const auto& s = paperField();
  diagnosis::DiagnoseConfig c;
  c.replicas = static_cast<int>(state.range(0));
  std::string cause;
  for (auto _ : state) {
    const auto r = diagnosis::diagnoseSequence(s.obs, c);
    cause = r.primary_cause;
    benchmark::DoNotOptimize(r);
  }
  state.SetLabel("cause " + cause);
}

void BM_DiagnoseStaticRoom(benchmark::State& state) {
  Scene scene;
  scene.sensor.beams = 360;
  scene.sensor.range.range_min_m = 0.15;
  scene.sensor.range.range_max_m = 12.0;
  scene.sensor.range.noise.kind = NoiseKind::squared;
  scene.sensor.range.noise.sigma_e = 0.0015;
  scene.path.stops = 1;
  scene.path.scans_per_stop = 150;
  scene.walls = {{-2.0, -3.0, 4.0, -3.0},
                 {4.0, -3.0, 4.0, 1.0},
                 {4.0, 1.0, 2.5, 3.5},
                 {2.5, 3.5, -2.0, 3.5},
                 {-2.0, 3.5, -2.0, -3.0}};
  const auto stops = simulation::planStops(scene, 1);
  diagnosis::StaticScans data;
  data.scans = 150;
  data.beams_per_scan = 360;
  data.range_min_m = 0.15;
  data.range_max_m = 12.0;
  for (std::size_t k = 0; k < data.scans; ++k)
    for (const auto& p : *simulation::simulateScan(scene, stops[0], k, 1).scan.cloud)
      if (std::isfinite(p.x))
        data.readings.push_back({std::atan2(static_cast<double>(p.y), static_cast<double>(p.x)),
                                 std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)),
                                 static_cast<std::uint32_t>(k)});
  diagnosis::DiagnoseConfig c;
  for (auto _ : state) benchmark::DoNotOptimize(diagnosis::diagnoseStatic(data, c));
  state.counters["readings"] = static_cast<double>(data.readings.size());
}

BENCHMARK(BM_CalibrateJoint)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DiagnoseSequence)->Arg(19)->Arg(39)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DiagnoseStaticRoom)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
