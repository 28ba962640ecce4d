// SPDX-License-Identifier: BSD-3-Clause
// Monte Carlo study throughput (docs/results/montecarlo.md): trials per second of the
// landmark level and the scan level, with and without the joint refinement, on 1 and 2 threads
// (the speed-up of the thread pool), and the joint refinement on every reading against the
// per-stop averages the study gives it.
//   build/bench/bench_montecarlo --benchmark_min_time=2
// Each iteration runs one batch of trials over the cells of Fig. 11 at L = 5 (sigma_theta 2 deg,
// four sigma_s); the counter trials_per_s is wall-clock trials per second.

#include <benchmark/benchmark.h>

#include <chrono>

#include "calibration/calibrate.hpp"
#include "common/rng.hpp"
#include "studies/draw.hpp"
#include "studies/runner.hpp"

namespace {

using namespace lidarcal;
using namespace lidarcal::studies;

std::vector<Cell> cells() {
  std::vector<Cell> c;
  for (double ss : {0.001, 0.01, 0.03, 0.1}) c.push_back(Cell{5, ss, deg2rad(2.0)});
  return c;
}

/// range(0): threads; range(1): 1 = joint refinement in every trial; range(2): trials per cell.
void runBatch(benchmark::State& state, Level level) {
  TrialConfig config;
  config.level = level;
  config.angle_noise = level == Level::scan ? AngleNoise::heading : AngleNoise::bearing;
  RunOptions o;
  o.threads = static_cast<int>(state.range(0));
  o.trials = static_cast<std::size_t>(state.range(2));
  o.joint_trials = state.range(1) ? o.trials : 0;
  const auto c = cells();
  std::size_t trials = 0;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto run = runCells(config, c, o);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    benchmark::DoNotOptimize(run);
    trials += c.size() * o.trials;
    ++o.seed;  // fresh trials each iteration
  }
  state.counters["trials_per_s"] = static_cast<double>(trials) / seconds;
}

void BM_LandmarkLevel(benchmark::State& state) { runBatch(state, Level::landmark); }
void BM_ScanLevel(benchmark::State& state) { runBatch(state, Level::scan); }

// {threads, joint, trials per cell}
BENCHMARK(BM_LandmarkLevel)
    ->Args({1, 0, 50})
    ->Args({2, 0, 50})
    ->Args({1, 1, 5})
    ->Args({2, 1, 5})
    ->Unit(benchmark::kSecond)
    ->UseRealTime();
BENCHMARK(BM_ScanLevel)
    ->Args({1, 0, 3})
    ->Args({2, 0, 3})
    ->Args({1, 1, 3})
    ->Args({2, 1, 3})
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

/// The joint refinement of one landmark-level draw (L = 5, 20 stops, 10 scans per stop) on every
/// reading, range(0) = 0, or on the per-stop beam averages the study feeds it, range(0) = 1.
void BM_JointInput(benchmark::State& state) {
  TrialConfig config;
  const Cell cell{5, 0.01, deg2rad(2.0)};
  const auto layout = trialLayout(config, 1, 0, 5);
  PathSpec path = config.path;
  path.sigma_s_m = cell.sigma_s_m;
  // the study's default angle noise: the heading per stop
  path.sigma_psi_rad = cell.sigma_theta_rad;
  const Draw d = drawLandmarkLevel(layout, path, config.sensor, 0.0, 1, false);
  const LandmarkObservations input = state.range(0) ? averageScans(d.obs) : d.obs;
  calibration::CalibrationConfig cc = estimatorConfig(config, cell);
  cc.method = calibration::Method::joint;
  std::size_t readings = 0;
  for (const auto& s : input.sightings) readings += s.beams.size();
  for (auto _ : state) {
    auto m = calibration::calibrate(input, cc);
    benchmark::DoNotOptimize(m);
  }
  state.counters["readings"] = static_cast<double>(readings);
}
BENCHMARK(BM_JointInput)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
