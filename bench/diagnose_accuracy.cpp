// SPDX-License-Identifier: BSD-3-Clause
// How often `diagnose` names an effect hidden in simulated data (docs/results/hidden-effects.md).
// Each case draws the size (and sign) of the effect from its own seed, simulates the paper
// field at the landmark level with it, diagnoses, and compares the named cause.
//   build/bench/diagnose_accuracy --effect heading_error --cases 20
//   build/bench/diagnose_accuracy --effect none --cases 20 --grid 0.001   (clean data on a 1 mm
//   grid)
//   build/bench/diagnose_accuracy --effect none --cases 20 --intensity    (clean data, poles of
//   several intensities)

#include <chrono>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include <CLI/CLI.hpp>

#include "common/rng.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/sequence.hpp"
#include "simulation/landmark_level.hpp"

int main(int argc, char** argv) {
  using namespace lidarcal;
  CLI::App app("diagnose accuracy on hidden effects");
  std::string effect = "none";
  int cases = 20, replicas = 19, first = 1;
  bool verbose = false;
  app.add_option("--effect", effect, "effect to hide (or none)");
  app.add_option("--cases", cases);
  app.add_option("--first", first, "first case seed");
  app.add_option("--replicas", replicas);
  app.add_flag("--verbose", verbose);
  double tails_dof = 0.0;
  app.add_option("--tails-dof", tails_dof,
                 "also make the noise a Student t of this many degrees of freedom (> 2): the "
                 "effect under heavy tails");
  double grid_m = 0.0;
  app.add_option("--grid", grid_m,
                 "also round the readings to this grid, metres (the effect on a sensor that "
                 "reports whole millimetres: 0.001)");
  bool intensity = false;
  app.add_flag(
      "--intensity", intensity,
      "also give the landmarks return intensities of 15-250 (dark_surface always has them)");
  CLI11_PARSE(app, argc, argv);
  int correct = 0;
  std::map<std::string, int> named;
  double total_s = 0.0;
  for (int c = first; c < first + cases; ++c) {
    auto hidden = test::hiddenEffectCase(effect, static_cast<std::uint64_t>(c));
    if (tails_dof > 2.0) hidden.config.effects.noise_student_dof = tails_dof;
    if (grid_m > 0.0) hidden.config.effects.range_resolution_m = grid_m;
    if (intensity && effect != "dark_surface")
      test::giveIntensities(hidden.config, static_cast<std::uint64_t>(c));
    const auto sample = simulation::simulateLandmarkLevel(hidden.config, hidden.seed);
    diagnosis::DiagnoseConfig dc;
    dc.replicas = replicas;
    dc.seed = static_cast<std::uint64_t>(c);
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = diagnosis::diagnoseSequence(sample.obs, dc, &sample.true_range_m);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    total_s += s;
    ++named[r.primary_cause];
    correct += r.primary_cause == effect;
    std::printf("case %d (%s): named %s in %.2f s [%s]\n", c, hidden.size.c_str(),
                r.primary_cause.c_str(), s, r.decision.c_str());
    if (verbose || r.primary_cause != effect)
      for (const auto& k : r.candidates)
        std::printf(
            "    %-16s p=%.2e holm=%.2e score p=%.1e es=%7.1f gain=%+.5f (se %.5f) dAIC=%9.1f k=%d "
            "id=%d (%.3f, se %.2g) mse=%.1f\n",
            toString(k.effect), k.p_value, k.p_holm, k.score_p_value, k.effect_size,
            k.heldout_gain_nats_per_point, k.heldout_gain_se, k.delta_aic, k.parameters,
            k.identifiable, k.information_ratio, k.standard_error, k.calibration_mse_ratio);
    if (verbose)
      for (const auto& k : r.candidates)
        for (const auto& [name, v] : k.estimates) std::printf("      %s = %.5g\n", name.c_str(), v);
  }
  std::printf("%s: %d / %d named correctly; mean %.2f s per case; named:", effect.c_str(), correct,
              cases, total_s / cases);
  for (const auto& [k, v] : named) std::printf(" %s %d", k.c_str(), v);
  std::printf("\n");
  return 0;
}
