// SPDX-License-Identifier: BSD-3-Clause
// How often `diagnose` (static mode) names what the truth allows in a room seen from one pose
// (docs/results/static-diagnosis.md): every case of tests/diagnosis/diagnose_cases.hpp,
// coarser quantisation grids, the clean room (its false-positive rate), and the tail cases
// (extra-wide errors only at grazing beams, at depth edges, on a dark wall; the tests
// draw their rooms from seeds they do not read), over many seeds.
//   build/bench/diagnose_static_accuracy [--seeds 10] [--clean-seeds 20] [--first 101] [--replicas
//                                        19] [--only NAME] [--dark-exponent DELTA] [--verbose]

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/static_scene.hpp"

/// One case's candidates, one line each (stderr): what decided the verdict.
void printCandidates(const char* name, int seed, const lidarcal::diagnosis::DiagnosisResult& r) {
  std::fprintf(stderr, "%s seed %d: %s\n", name, seed, r.primary_cause.c_str());
  for (const auto& c : r.candidates)
    std::fprintf(stderr,
                 "  %-16s gain %+.4f +- %.4f  p_heldout %.2g  score_p %.2g  p_holm %.2g  %s\n",
                 toString(c.effect), c.heldout_gain_nats_per_point, c.heldout_gain_se, c.p_heldout,
                 c.score_p_value, c.p_holm, c.significant ? "significant" : "");
  for (const auto& c : r.candidates)
    for (const auto& [k, v] : c.estimates)
      std::fprintf(stderr, "    %s %s = %.6g\n", toString(c.effect), k.c_str(), v);
}

/// Extra-wide errors (10 % of the readings of one class of beams, 5 cm): how often the physical
/// cause is named and the tails put in the right class of beams.
void tailCases(int seeds, int first, int replicas, const std::string& only, bool verbose) {
  using namespace lidarcal;
  struct Case {
    const char* name;
    test::TailWhere where;
    const char* effect;
    const char* cls;
  };
  for (const Case& c :
       {Case{"tails_grazing", test::TailWhere::grazing, "incidence_noise", "grazing"},
        Case{"tails_edge", test::TailWhere::edge, "mixed_pixels", "edge"},
        Case{"tails_dark", test::TailWhere::dark, "dark_surface", "dark"}}) {
    if (!only.empty() && std::string(c.name).find(only) == std::string::npos) continue;
    std::map<std::string, int> named;
    int right = 0, cls_right = 0;
    for (int seed = first; seed < first + seeds; ++seed) {
      diagnosis::DiagnoseConfig dc;
      dc.replicas = replicas;
      dc.seed = static_cast<std::uint64_t>(seed);
      const auto r = diagnosis::diagnoseStatic(
          test::staticRoomWithTails(c.where, 0.10, 0.05, static_cast<std::uint64_t>(seed)), dc);
      const std::string top = test::dominantTailClass(r.tails);
      if (verbose) {
        printCandidates(c.name, seed, r);
        std::fprintf(stderr, "  decision: %s\n  tails: pooled %.3f, cause %s;", r.decision.c_str(),
                     r.tails.pooled_fraction, r.tails.cause.c_str());
        for (const auto& [k, v] : r.tails.robust) std::fprintf(stderr, " %s %.4g", k.c_str(), v);
        std::fprintf(stderr, "\n");
      }
      right += r.primary_cause == c.effect;
      cls_right += top == c.cls;
      if (r.primary_cause != c.effect) ++named[r.primary_cause];
    }
    std::string other;
    for (const auto& [k, v] : named)
      other += (other.empty() ? "" : ", ") + k + " " + std::to_string(v);
    std::printf("| %s | %s | %d | %d / %d (tails in class %s: %d / %d) | %s |\n", c.name, c.effect,
                seeds, right, seeds, c.cls, cls_right, seeds, other.empty() ? "-" : other.c_str());
    std::fflush(stdout);
  }
}

int main(int argc, char** argv) {
  using namespace lidarcal;
  CLI::App app("static-mode diagnosis accuracy");
  int seeds = 10, clean_seeds = 20, first = 101, replicas = 19;
  app.add_option("--seeds", seeds, "seeds per effect");
  app.add_option("--clean-seeds", clean_seeds, "seeds of the clean room");
  app.add_option("--first", first, "first seed (the tests use 7)");
  app.add_option("--replicas", replicas, "bootstrap replicas");
  std::string only;
  app.add_option("--only", only,
                 "run only the cases whose name contains this (tails_: the tail cases)");
  double dark_exponent = 0.0;
  app.add_option("--dark-exponent", dark_exponent,
                 "the dark_surface case's exponent delta instead of 0.75 (its detection limit)");
  bool verbose = false;
  app.add_flag("--verbose", verbose,
               "print every case's candidates (held-out gain, p-values) to stderr");
  CLI11_PARSE(app, argc, argv);
  std::vector<test::StaticCase> cases = test::staticCases();
  for (auto& c : cases)
    if (dark_exponent != 0.0 && c.fx.dark_noise_exponent != 0.0)
      c.fx.dark_noise_exponent = dark_exponent;
  for (double grid : {0.005, 0.01}) {
    RangeEffects fx;
    fx.range_resolution_m = grid;
    const test::StaticCase c{
        grid == 0.005 ? "quantisation_5mm" : "quantisation_10mm", "quantisation", {}, fx};
    cases.push_back(c);
  }
  cases.insert(cases.begin(), test::StaticCase{"clean", "none", {}, RangeEffects{}});
  std::printf(
      "| case | allowed | seeds | named as allowed | otherwise named |\n|---|---|---|---|---|\n");
  for (const auto& c : cases) {
    if (!only.empty() && std::string(c.name).find(only) == std::string::npos) continue;
    const int n = std::string(c.name) == "clean" ? clean_seeds : seeds;
    std::map<std::string, int> named;
    int right = 0;
    for (int seed = first; seed < first + n; ++seed) {
      diagnosis::DiagnoseConfig dc;
      dc.replicas = replicas;
      dc.seed = static_cast<std::uint64_t>(seed);
      dc.static_range_offset_m = c.known_offset_m;
      const auto r =
          diagnosis::diagnoseStatic(test::staticRoom(c, static_cast<std::uint64_t>(seed)), dc);
      const bool ok = c.allows(r.primary_cause);
      right += ok;
      if (verbose) printCandidates(c.name, seed, r);
      if (!ok) ++named[r.primary_cause];
    }
    std::string other;
    for (const auto& [k, v] : named)
      other += (other.empty() ? "" : ", ") + k + " " + std::to_string(v);
    std::string allowed = c.effect;
    for (const auto& a : c.also) allowed += " or " + a;
    std::printf("| %s | %s | %d | %d / %d | %s |\n", c.name, allowed.c_str(), n, right, n,
                other.empty() ? "-" : other.c_str());
    std::fflush(stdout);
  }
  tailCases(seeds, first, replicas, only, verbose);
  return 0;
}
