// SPDX-License-Identifier: BSD-3-Clause
// Calibration cost (docs/results/calibration-accuracy.md): the paper's closed form and our joint
// refinement on the same data, 20 stops x 5 landmarks, one scan per stop and ten; and
// `lidarcal run` on the bundled example next to the time to only read and write its PCD files.
//   build/bench/bench_calibration --benchmark_min_time=1

#include <cstdlib>
#include <filesystem>

#include <benchmark/benchmark.h>

#include "io/pcd_scan.hpp"
#include "io/sequence.hpp"

#include "calibration/calibrate.hpp"
#include "simulation/landmark_level.hpp"

namespace {

using namespace lidarcal;

simulation::LandmarkLevelSample sample(int scans_per_stop) {
  simulation::LandmarkLevelConfig c;
  c.landmarks = {
      {1.5, 0.75, 0.12}, {0.3, 2.2, 0.12}, {2.4, 3.4, 0.12}, {3.9, -1.3, 0.12}, {0.9, -2.8, 0.12}};
  c.path.stops = 20;
  c.path.step_m = 0.15;
  c.path.scans_per_stop = scans_per_stop;
  c.path.sigma_s_m = 0.02;
  c.path.sigma_psi_rad = deg2rad(0.5);
  c.model.bias.alpha = {0.0525, 0.8838, 0.0584};
  c.model.noise.kind = NoiseKind::squared;
  c.model.noise.sigma_e = 0.0019176;
  c.model.range_min_m = 0.2;
  c.model.range_max_m = 6.0;
  c.sigma_theta_rad = deg2rad(0.2);
  c.beams = true;
  return simulation::simulateLandmarkLevel(c, 1);
}

void run(benchmark::State& state, calibration::Method method) {
  const auto s = sample(static_cast<int>(state.range(0)));
  calibration::CalibrationConfig config;
  config.method = method;
  std::size_t readings = 0;
  for (const auto& sg : s.obs.sightings) readings += sg.beams.size();
  for (auto _ : state) {
    auto m = calibration::calibrate(s.obs, config);
    benchmark::DoNotOptimize(m);
  }
  state.counters["readings"] = static_cast<double>(readings);
  state.counters["sightings"] = static_cast<double>(s.obs.sightings.size());
}

void BM_ClosedForm(benchmark::State& state) { run(state, calibration::Method::closed_form); }
void BM_Joint(benchmark::State& state) { run(state, calibration::Method::joint); }

BENCHMARK(BM_ClosedForm)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Joint)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond);

const std::filesystem::path kExample =
    std::filesystem::path(LIDARCAL_SOURCE_DIR) / "data/example/scans";

/// The main job on the bundled example (detect, calibrate, correct, report), as a process.
void BM_RunExample(benchmark::State& state) {
  const auto out = std::filesystem::temp_directory_path() / "lidarcal-bench-run";
  const std::string cmd = std::string(LIDARCAL_EXE) + " run -q --no-truth " + kExample.string() +
                          " --out " + out.string() + " --overwrite >/dev/null";
  for (auto _ : state)
    if (std::system(cmd.c_str()) != 0) state.SkipWithError("lidarcal run failed");
  std::filesystem::remove_all(out);
}

/// The I/O floor: read every scan of the example and write it again (what correct must do).
void BM_ReadWriteExample(benchmark::State& state) {
  const auto seq = io::openSequence(kExample);
  const auto out = std::filesystem::temp_directory_path() / "lidarcal-bench-io";
  std::filesystem::create_directories(out);
  for (auto _ : state)
    for (const auto& h : seq.scans) io::writeScan(out / h.name(), io::readScan(h.path));
  std::filesystem::remove_all(out);
}

BENCHMARK(BM_RunExample)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ReadWriteExample)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
