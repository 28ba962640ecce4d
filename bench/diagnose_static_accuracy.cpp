// How often `diagnose` (static mode) names what the truth allows in a room seen from one pose
// (docs/RESULTS.md, "Diagnosis", static mode): every case of tests/diagnosis/diagnose_cases.hpp,
// coarser quantisation grids, and the clean room (its false-positive rate), over many seeds.
//   build/bench/diagnose_static_accuracy [--seeds 10] [--clean-seeds 20] [--first 101] [--replicas 19]

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/static_scene.hpp"

int main(int argc, char** argv) {
  using namespace lidarcal;
  CLI::App app("static-mode diagnosis accuracy");
  int seeds = 10, clean_seeds = 20, first = 101, replicas = 19;
  app.add_option("--seeds", seeds, "seeds per effect");
  app.add_option("--clean-seeds", clean_seeds, "seeds of the clean room");
  app.add_option("--first", first, "first seed (the tests use 7)");
  app.add_option("--replicas", replicas, "bootstrap replicas");
  CLI11_PARSE(app, argc, argv);
  std::vector<test::StaticCase> cases = test::staticCases();
  for (double grid : {0.005, 0.01}) {
    RangeEffects fx;
    fx.range_resolution_m = grid;
    const test::StaticCase c{grid == 0.005 ? "quantisation_5mm" : "quantisation_10mm", "quantisation", {}, fx};
    cases.push_back(c);
  }
  cases.insert(cases.begin(), test::StaticCase{"clean", "none", {}, RangeEffects{}});
  std::printf("| case | allowed | seeds | named as allowed | otherwise named |\n|---|---|---|---|---|\n");
  for (const auto& c : cases) {
    const int n = std::string(c.name) == "clean" ? clean_seeds : seeds;
    std::map<std::string, int> named;
    int right = 0;
    for (int seed = first; seed < first + n; ++seed) {
      diagnosis::DiagnoseConfig dc;
      dc.replicas = replicas;
      dc.seed = static_cast<std::uint64_t>(seed);
      dc.static_range_offset_m = c.known_offset_m;
      const auto r = diagnosis::diagnoseStatic(test::staticRoom(c.fx, c.noise, static_cast<std::uint64_t>(seed), 150, c.step_error_fraction), dc);
      const bool ok = c.allows(r.primary_cause);
      right += ok;
      if (!ok) ++named[r.primary_cause];
    }
    std::string other;
    for (const auto& [k, v] : named) other += (other.empty() ? "" : ", ") + k + " " + std::to_string(v);
    std::string allowed = c.effect;
    for (const auto& a : c.also) allowed += " or " + a;
    std::printf("| %s | %s | %d | %d / %d | %s |\n", c.name, allowed.c_str(), n, right, n,
                other.empty() ? "-" : other.c_str());
    std::fflush(stdout);
  }
  return 0;
}
