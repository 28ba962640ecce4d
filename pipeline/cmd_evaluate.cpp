// lidarcal evaluate OUT --truth truth.json [--raw RAW]: MSE ratio of raw vs corrected ranges.

#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/papers.hpp"
#include "pipeline/truth_eval.hpp"

namespace lidarcal::pipeline {
namespace {

nlohmann::ordered_json toJson(const calibration::RangeComparison& c) {
  return nlohmann::ordered_json{{"n", c.n},
                                {"mse_raw_m2", c.mse_raw_m2},
                                {"mse_corrected_m2", c.mse_corrected_m2},
                                {"mse_ratio", c.mse_ratio},
                                {"nmse_raw", c.nmse_raw},
                                {"nmse_corrected", c.nmse_corrected}};
}

}  // namespace

nlohmann::ordered_json evaluationJson(const Evaluation& e) {
  return nlohmann::ordered_json{{"scans", e.scans},
                                {"lost_returns", e.lost},
                                {"landmarks", toJson(e.landmarks)},
                                {"walls", toJson(e.walls)},
                                {"all", toJson(e.all)}};
}

void addEvaluateCommand(CLI::App& app) {
  struct Options {
    std::string corrected, truth, raw, out;
  };
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "evaluate", std::string("Compare corrected and raw ranges of a simulated sequence with the truth: MSE ratio (raw MSE / "
                              "corrected MSE, higher is better; ") +
                      papers::kLandmarks + ", eq. 31) and normalised MSE (" + papers::kTriangulation + ", eqs. 31-32), as JSON");
  sub->add_option("OUT", o->corrected, "Corrected sequence (from lidarcal correct)")->required();
  sub->add_option("--truth", o->truth, "truth.json written by lidarcal simulate")->required();
  sub->add_option("--raw", o->raw, "Raw sequence (default: the scans/ directory next to truth.json)");
  sub->add_option("-o,--out", o->out, "Also write the JSON to this file");
  sub->callback([o] {
    namespace fs = std::filesystem;
    if (!o->out.empty()) {
      io::checkOutsideInput(o->corrected, o->out);
      io::checkOutputFile(o->out, true);
    }
    const SimulationTruth truth = loadTruth(o->truth);
    const fs::path raw = o->raw.empty() ? fs::path(o->truth).parent_path() / "scans" : fs::path(o->raw);
    const Evaluation e = evaluate(io::openSequence(o->corrected), io::openSequence(raw), truth);
    const std::string text = evaluationJson(e).dump(2) + "\n";
    std::fputs(text.c_str(), stdout);
    if (!o->out.empty()) io::writeTextAtomically(o->out, text);
  });
}

}  // namespace lidarcal::pipeline
