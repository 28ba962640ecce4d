// SPDX-License-Identifier: BSD-3-Clause
// Per-scan work of the live nodes side by side (budget: <= 0.2 ms per 360-beam scan, <= 1 ms per
// 1081-beam scan). ROS 1 (`lidarcal_node`): copy the received ranges and correct them with
// pipeline::correctLaserRanges, as its callback does. ROS 2 (`lidarcal_ros2_node`, names
// `Ros2...`): ros2::LiveCorrector::process on the received sample's ranges in place, as its
// callback does (the checks of a malformed scan, the copy in and out, the same correction). The
// transports (roscpp, DDS) are not included in either. Bias polynomials of
// order 2 (closed-form LS) and 3 (polynomial roots), LS and ML inversion; readings spread over
// 0.3-10 m with a fitted range of 0.5-8 m (some readings beyond it, continued as by default),
// quantised to 1 mm as the sensors report them. `Steady`: the node after its first scans (the
// MemoCorrector has seen the readings); `Cold`: a fresh corrector per scan (the first scans after
// start, every reading a root search).
//
//   build/bench/bench_ros_node        (Time = per scan)
// Measured (Release, 2 shared cores, time per scan, medians of 3): steady 10 us / 360 beams and
// 31 us / 1081 beams whatever the model; cold, LS order 2: 45 / 130 us; LS order 3: 48 / 136 us;
// ML order 3: 121 / 346 us. The same bench built at 12f7489 (eigenvalue roots per reading), run
// beside it: LS order 3 581 / 1678 us, ML order 3 1776 / 5130 us. ROS 2 beside ROS 1 in one run
// (CPU time per scan, medians of 3, 360 / 1081 beams; the machine busy with a build, so wall
// times ran 3x higher): steady 7.8 / 22.4 us (ROS 1: 7.4 / 22.4); cold LS order 3 35 / 101 us
// (ROS 1: 35 / 98); cold ML order 3 87 / 247 us (ROS 1: 84 / 246).

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "pipeline/stages/bag_correct.hpp"
#include "ros2/live_corrector.hpp"

namespace {

using namespace lidarcal;

CalibrationModel model(int order) {
  CalibrationModel m;
  m.model.bias.alpha = order == 2 ? std::vector<double>{0.03, 0.98, 0.004}
                                  : std::vector<double>{0.03, 0.98, 0.004, -0.0001};
  m.model.noise.kind = NoiseKind::squared;
  m.model.noise.sigma_e = 0.002;
  m.model.range_min_m = 0.15;
  m.model.range_max_m = 12.0;
  m.fitted_range_m = std::make_pair(0.5, 8.0);
  return m;
}

void correctScan(benchmark::State& state, int order, calibration::InversionMethod method,
                 bool cold) {
  const auto beams = static_cast<std::size_t>(state.range(0));
  const CalibrationModel m = model(order);
  const calibration::ReadingCorrector correct =
      calibration::readingCorrector(m, method, calibration::kDefaultOutside);
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> reading_mm(300, 10000);
  // 200 scans of a sensor whose readings are whole millimetres.
  std::vector<std::vector<float>> received(200, std::vector<float>(beams));
  for (auto& scan : received)
    for (float& r : scan) r = static_cast<float>(reading_mm(rng)) * 0.001f;
  pipeline::CorrectionStats stats;
  pipeline::MemoCorrector warm(correct);
  for (const auto& scan : received) {  // the node's first 200 scans
    std::vector<float> ranges = scan;
    pipeline::correctLaserRanges(ranges, 0.15, 12.0, warm, stats);
  }
  std::size_t k = 0;
  for (auto _ : state) {
    // the node copies the received message
    std::vector<float> ranges = received[k++ % received.size()];
    if (cold) {
      pipeline::MemoCorrector fresh(correct);
      pipeline::correctLaserRanges(ranges, 0.15, 12.0, fresh, stats);
    } else {
      pipeline::correctLaserRanges(ranges, 0.15, 12.0, warm, stats);
    }
    benchmark::DoNotOptimize(ranges.data());
  }
}

/// The ROS 2 node's callback: ros2::LiveCorrector on the sample's ranges (corrected in place, so
/// each iteration first restores the received values, as a new sample would bring them).
void ros2Scan(benchmark::State& state, int order, calibration::InversionMethod method, bool cold) {
  const auto beams = static_cast<std::size_t>(state.range(0));
  const CalibrationModel m = model(order);
  const calibration::ReadingCorrector correct =
      calibration::readingCorrector(m, method, calibration::kDefaultOutside);
  ros2::LiveSettings settings;
  settings.model_file = "model.json";
  settings.topic = "/scan";
  settings.method = method;
  settings.outside = calibration::kDefaultOutside;
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> reading_mm(300, 10000);
  std::vector<std::vector<float>> received(200, std::vector<float>(beams));
  for (auto& scan : received)
    for (float& r : scan) r = static_cast<float>(reading_mm(rng)) * 0.001f;
  std::vector<float> sample(beams);
  auto fields = [&](const std::vector<float>& scan) {
    sample = scan;  // the sample as Cyclone hands it over
    ros2::ScanFields f;
    f.angle_min = -3.1f;
    f.angle_increment = 0.0174f;
    f.angle_max = f.angle_min + f.angle_increment * static_cast<float>(beams - 1);
    f.range_min = 0.15f;
    f.range_max = 12.0f;
    f.ranges = sample.data();
    f.beams = beams;
    return f;
  };
  ros2::LiveCorrector warm(m, settings, correct);
  for (const auto& scan : received) {  // the node's first 200 scans
    ros2::ScanFields f = fields(scan);
    warm.process(f);
  }
  std::size_t k = 0;
  for (auto _ : state) {
    ros2::ScanFields f = fields(received[k++ % received.size()]);
    if (cold) {
      ros2::LiveCorrector fresh(m, settings, correct);
      benchmark::DoNotOptimize(fresh.process(f));
    } else {
      benchmark::DoNotOptimize(warm.process(f));
    }
    benchmark::DoNotOptimize(sample.data());
  }
}

void SteadyLsOrder2(benchmark::State& s) {
  correctScan(s, 2, calibration::InversionMethod::ls, false);
}
void SteadyLsOrder3(benchmark::State& s) {
  correctScan(s, 3, calibration::InversionMethod::ls, false);
}
void SteadyMlOrder3(benchmark::State& s) {
  correctScan(s, 3, calibration::InversionMethod::ml, false);
}
void ColdLsOrder2(benchmark::State& s) {
  correctScan(s, 2, calibration::InversionMethod::ls, true);
}
void ColdLsOrder3(benchmark::State& s) {
  correctScan(s, 3, calibration::InversionMethod::ls, true);
}
void ColdMlOrder3(benchmark::State& s) {
  correctScan(s, 3, calibration::InversionMethod::ml, true);
}
void Ros2SteadyLsOrder2(benchmark::State& s) {
  ros2Scan(s, 2, calibration::InversionMethod::ls, false);
}
void Ros2SteadyLsOrder3(benchmark::State& s) {
  ros2Scan(s, 3, calibration::InversionMethod::ls, false);
}
void Ros2SteadyMlOrder3(benchmark::State& s) {
  ros2Scan(s, 3, calibration::InversionMethod::ml, false);
}
void Ros2ColdLsOrder2(benchmark::State& s) {
  ros2Scan(s, 2, calibration::InversionMethod::ls, true);
}
void Ros2ColdLsOrder3(benchmark::State& s) {
  ros2Scan(s, 3, calibration::InversionMethod::ls, true);
}
void Ros2ColdMlOrder3(benchmark::State& s) {
  ros2Scan(s, 3, calibration::InversionMethod::ml, true);
}

}  // namespace

BENCHMARK(SteadyLsOrder2)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(SteadyLsOrder3)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(SteadyMlOrder3)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(ColdLsOrder2)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(ColdLsOrder3)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(ColdMlOrder3)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2SteadyLsOrder2)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2SteadyLsOrder3)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2SteadyMlOrder3)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2ColdLsOrder2)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2ColdLsOrder3)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK(Ros2ColdMlOrder3)->Arg(360)->Arg(1081)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
