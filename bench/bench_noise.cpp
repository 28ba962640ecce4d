// SPDX-License-Identifier: BSD-3-Clause
// Wall time of noise estimation on the same data: Sharma 2020's KL hill climbing (our variant;
// the seed's settings: 80 particles, step 0.01, 5 jumps, means and variances climbed; `Literal`:
// all 80 particles run even when they stay identical) against the ML estimator (estimating the
// process noise too, or told it as the hill climbing is: `ProcessGiven`), in the
// settings of Sharma 2020's experiments 2 and 3 (data/scenes/noise_exp12.json, noise_exp3.json,
// simulator seed 1). Numbers: docs/results/noise-consistency.md.
//
//   build/bench/bench_noise --benchmark_counters_tabular=true

#include <benchmark/benchmark.h>

#include "io/noise_json.hpp"
#include "noise/problem.hpp"
#include "pipeline/stages/noise_run.hpp"
#include "simulation/observation_sim.hpp"

namespace {

using namespace lidarcal;

struct Data {
  noise::NoiseProblem problem;
  NoiseSetting init;
};

Data load(const char* scene, const char* init) {
  const std::string root = LIDARCAL_SOURCE_DIR;
  const auto sim =
      simulation::simulateObservations(io::readObservationScene(root + "/data/scenes/" + scene), 1);
  return Data{noise::makeNoiseProblem(sim.observations, sim.odometry),
              io::readNoiseSetting(root + "/data/noise/" + init)};
}

void run(benchmark::State& state, const Data& d, pipeline::NoiseMethod method, bool literal = false,
         bool process_given = false) {
  pipeline::NoiseRunOptions o;
  o.method = method;
  o.initial = d.init;
  // process_given (ml): told the process noise of the start, as the hill climbing is.
  o.ml.estimate_process = !process_given;
  // literal: all 80 particles even when they stay identical (no process noise), as the seed runs.
  o.kl.objective.filter.collapse_identical_particles = !literal;
  int evaluations = 0;
  for (auto _ : state) {
    const pipeline::NoiseRun r = pipeline::runNoiseEstimation(d.problem, o);
    evaluations = r.evaluations;
    benchmark::DoNotOptimize(r.noise.sensors.data());
  }
  state.counters["evaluations"] = evaluations;
  state.counters["observations"] = static_cast<double>(d.problem.observations.size());
}

const Data& exp2() {
  static const Data d = load("noise_exp12.json", "exp2_init.json");
  return d;
}
const Data& exp3() {
  static const Data d = load("noise_exp3.json", "exp3_init.json");
  return d;
}

void BM_Exp2_KlHill_Literal(benchmark::State& s) {
  run(s, exp2(), pipeline::NoiseMethod::kl_hill, true);
}
void BM_Exp2_KlHill(benchmark::State& s) { run(s, exp2(), pipeline::NoiseMethod::kl_hill); }
void BM_Exp2_Ml(benchmark::State& s) { run(s, exp2(), pipeline::NoiseMethod::ml); }
void BM_Exp2_Ml_ProcessGiven(benchmark::State& s) {
  run(s, exp2(), pipeline::NoiseMethod::ml, false, true);
}
void BM_Exp3_KlHill(benchmark::State& s) { run(s, exp3(), pipeline::NoiseMethod::kl_hill); }
void BM_Exp3_Ml(benchmark::State& s) { run(s, exp3(), pipeline::NoiseMethod::ml); }
void BM_Exp3_Ml_ProcessGiven(benchmark::State& s) {
  run(s, exp3(), pipeline::NoiseMethod::ml, false, true);
}

BENCHMARK(BM_Exp2_KlHill_Literal)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_Exp2_KlHill)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_Exp2_Ml)->Unit(benchmark::kSecond)->Iterations(3);
BENCHMARK(BM_Exp2_Ml_ProcessGiven)->Unit(benchmark::kSecond)->Iterations(3);
BENCHMARK(BM_Exp3_KlHill)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_Exp3_Ml)->Unit(benchmark::kSecond)->Iterations(3);
BENCHMARK(BM_Exp3_Ml_ProcessGiven)->Unit(benchmark::kSecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
