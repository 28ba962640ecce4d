// SPDX-License-Identifier: BSD-3-Clause
// lidarcal evaluate OUT --truth truth.json [--raw RAW]: a simulated sequence's corrected ranges
// against the simulator's true ones, raw vs corrected (MSE ratio, normalised MSE), as JSON.
// lidarcal evaluate SEQ --reference REF.json [--model M]: what the scans read at the distances and
// spans you measured, raw and with M corrected, each entry against the model's intervals.

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "calibration/error_summary.hpp"
#include "calibration/predictive_check.hpp"
#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_number.hpp"
#include "io/model_io.hpp"
#include "io/reference_io.hpp"
#include "pipeline/commands/cli_options.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/evaluation_json.hpp"
#include "pipeline/reports/model_text.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/reports/predictive_report.hpp"
#include "pipeline/stages/reference_stage.hpp"

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

nlohmann::ordered_json evaluationJson(const calibration::Evaluation& e) {
  return nlohmann::ordered_json{{"scans", e.scans},
                                {"lost_returns", e.lost},
                                {"landmarks", toJson(e.landmarks)},
                                {"walls", toJson(e.walls)},
                                {"all", toJson(e.all)},
                                {"beyond_fitted_range", toJson(e.beyond)}};
}

namespace {

/// Whether a reference distance lies within the distances the model was fitted over (all do
/// without a model or a recorded range).
bool inFittedRange(const calibration::ReferenceMatch& m, const CalibrationModel* model) {
  if (!model || !model->fitted_range_m) return true;
  return m.surface_m >= model->fitted_range_m->first - 1e-3 &&
         m.surface_m <= model->fitted_range_m->second + 1e-3;
}

nlohmann::ordered_json matchJson(const calibration::ReferenceMatch& m,
                                 const CalibrationModel* model) {
  nlohmann::ordered_json j{{"entry", m.entry},
                           {"stop", m.stop},
                           {"target", m.target == ReferenceTarget::wall ? "wall" : "landmark"},
                           {"reference_m", m.reference_m},
                           {"in_fitted_range", inFittedRange(m, model)},
                           {"status", m.status}};
  if (m.ok()) {
    j["measured_m"] = m.measured_m;
    j["measured_se_m"] = io::jsonNumber(m.measured_se_m);
    j["error_m"] = m.measured_m - m.reference_m;
    j["scans"] = m.sightings;
    j["readings"] = m.readings;
  }
  return j;
}

/// measured - reference of the matched entries (with `model`: those inside its fitted range only).
std::vector<double> entryErrors(const std::vector<calibration::ReferenceMatch>& matches,
                                const CalibrationModel* model = nullptr) {
  std::vector<double> e;
  for (const auto& m : matches)
    if (m.ok() && inFittedRange(m, model)) e.push_back(m.measured_m - m.reference_m);
  return e;
}

/// The RMS of measured - reference over those entries and its standard error, as E.json keys.
void addRms(nlohmann::ordered_json& j, const std::vector<calibration::ReferenceMatch>& matches,
            const CalibrationModel* model) {
  const calibration::RmsError e = calibration::rmsError(entryErrors(matches, model));
  j["rms_error_m"] = io::jsonNumber(e.rms_m);
  j["rms_error_se_m"] = io::jsonNumber(e.se_m);
  j["rms_error_all_m"] = io::jsonNumber(calibration::rmsError(entryErrors(matches)).rms_m);
}

/// Raw against corrected over the entries matched in both and inside the model's fitted range.
calibration::MseRatio pairedMseRatio(const std::vector<calibration::ReferenceMatch>& raw,
                                     const std::vector<calibration::ReferenceMatch>& corrected,
                                     const CalibrationModel& model) {
  std::vector<double> r, c;
  for (std::size_t k = 0; k < raw.size() && k < corrected.size(); ++k)
    if (raw[k].ok() && corrected[k].ok() && inFittedRange(raw[k], &model))
      r.push_back(raw[k].measured_m - raw[k].reference_m),
          c.push_back(corrected[k].measured_m - corrected[k].reference_m);
  return calibration::mseRatio(r, c);
}

nlohmann::ordered_json spanJson(const calibration::SpanMatch& m) {
  nlohmann::ordered_json j{
      {"entry", m.entry}, {"stop", m.stop}, {"reference_m", m.reference_m}, {"status", m.status}};
  if (m.ok()) {
    j["measured_m"] = m.measured_m;
    j["measured_se_m"] = io::jsonNumber(m.measured_se_m);
    j["error_m"] = m.measured_m - m.reference_m;
    j["scans"] = m.scans;
  }
  return j;
}

/// The spans part of E.json: each span as the scans measure it, and the RMS over those found
/// with its standard error.
nlohmann::ordered_json spansJson(const std::vector<calibration::SpanMatch>& matches) {
  auto entries = nlohmann::ordered_json::array();
  std::vector<double> errors;
  for (const auto& m : matches) {
    entries.push_back(spanJson(m));
    if (m.ok()) errors.push_back(m.measured_m - m.reference_m);
  }
  const calibration::RmsError e = calibration::rmsError(errors);
  return {{"rms_error_m", io::jsonNumber(e.rms_m)},
          {"rms_error_se_m", io::jsonNumber(e.se_m)},
          {"entries", entries}};
}

/// The command line of `evaluate`.
struct EvaluateOptions {
  std::string corrected, truth, raw, out, reference, model,
      inversion = "ls", outside = calibration::toString(calibration::kDefaultOutside);
  double radius_m = 0.0;
  bool force = false;
};

/// evaluate SEQ --reference REF.json [--model model.json]: what the scans measure at the
/// reference distances and spans, raw and corrected.
void evaluateReference(const EvaluateOptions& o) {
  const std::string &seq_dir = o.corrected, &ref_file = o.reference, &model_file = o.model;
  const std::string &inversion = o.inversion, &out = o.out;
  const bool force = o.force;
  const io::Sequence seq = io::openSequence(seq_dir);
  const Reference ref = io::readReference(ref_file);
  io::checkReference(ref, seq.stops.size(), ref_file);
  calibration::Outside outside = calibration::kDefaultOutside;
  calibration::parseOutside(o.outside, outside);  // checked by the option
  CalibrationOptions options;
  options.radius_m = o.radius_m;
  const auto detection = referenceDetection(detectionConfig(options));
  Progress raw_progress("measure (raw)", seq.scans.size());
  const auto raw = observeReference(seq, ref, detection, scanLoader(seq),
                                    [&](std::size_t d, std::size_t) { raw_progress.update(d); });
  raw_progress.finish();
  requireDistinctTargets(raw.known, ref_file);
  nlohmann::ordered_json j{{"sequence", seq_dir}, {"reference", ref_file}};
  std::optional<CalibrationModel> model;
  if (!model_file.empty()) model = io::readModel(model_file);
  const CalibrationModel* fitted = model ? &*model : nullptr;
  auto raw_json = nlohmann::ordered_json::array();
  for (const auto& m : raw.known.matches) raw_json.push_back(matchJson(m, fitted));
  // With a model, the RMS over the entries inside its fitted range (readings outside are kept
  // raw by default) and over all of them.
  j["raw"] = nlohmann::ordered_json::object();
  addRms(j["raw"], raw.known.matches, fitted);
  j["raw"]["entries"] = raw_json;
  if (!ref.spans.empty()) j["raw"]["spans"] = spansJson(raw.spans.matches);
  std::optional<ReferenceObservations> corrected;
  std::optional<calibration::PredictiveCheck> check;  // each distance against the model's intervals
  if (model) {
    if (const std::string w = checkModelFits(*model, seq, model_file, force, outside); !w.empty())
      std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
    const auto method =
        inversion == "ml" ? calibration::InversionMethod::ml : calibration::InversionMethod::ls;
    const calibration::ReadingCorrector correction =
        calibration::readingCorrector(*model, method, outside);
    Progress cor_progress("measure (corrected)", seq.scans.size());
    corrected = observeReference(seq, ref, detection, scanLoader(seq, &correction),
                                 [&](std::size_t d, std::size_t) { cor_progress.update(d); });
    cor_progress.finish();
    auto cor_json = nlohmann::ordered_json::array();
    for (const auto& m : corrected->known.matches) cor_json.push_back(matchJson(m, fitted));
    j["model"] = model_file;
    j["corrected"] = nlohmann::ordered_json::object();
    addRms(j["corrected"], corrected->known.matches, fitted);
    const calibration::MseRatio ratio =
        pairedMseRatio(raw.known.matches, corrected->known.matches, *model);
    j["corrected"]["mse_ratio"] = {{"ratio", io::jsonNumber(ratio.ratio)},
                                   {"low_95", io::jsonNumber(ratio.low)},
                                   {"high_95", io::jsonNumber(ratio.high)},
                                   {"entries", ratio.entries}};
    j["corrected"]["entries"] = cor_json;
    if (!ref.spans.empty()) j["corrected"]["spans"] = spansJson(corrected->spans.matches);
    if (!ref.distances.empty())
      check = calibration::predictiveCheck(corrected->known.matches, ref, *model, correction);
    if (check) j["predictive"] = predictiveJson(*check);
  }
  if (!ref.distances.empty())
    std::fputs(referenceTable(raw.known.matches, corrected ? &corrected->known.matches : nullptr,
                              fitted, outside)
                   .c_str(),
               stdout);
  if (check) std::fputs(predictiveTable(*check).c_str(), stdout);
  if (!ref.spans.empty())
    std::fputs(
        spanEvaluationTable(raw.spans.matches, corrected ? &corrected->spans.matches : nullptr)
            .c_str(),
        stdout);
  if (!out.empty()) io::writeTextAtomically(out, j.dump(2) + "\n");
}

}  // namespace

void addEvaluateCommand(CLI::App& app) {
  auto o = std::make_shared<EvaluateOptions>();
  CLI::App* sub = app.add_subcommand(
      "evaluate",
      std::string(
          "Compare a sequence with the truth: with --truth, corrected vs raw ranges of a simulated "
          "sequence (MSE ratio = raw MSE / corrected MSE, higher is better; ") +
          papers::kLandmarks + ", eq. 31; normalised MSE, " + papers::kTriangulation +
          ", eqs. 31-32), as JSON; with --reference, what the scans measure at distances you "
          "measured, raw "
          "and (with --model) corrected");
  sub->add_option("SEQ", o->corrected,
                  "With --truth: the corrected sequence (from lidarcal correct); with --reference: "
                  "the raw sequence")
      ->required();
  auto* truth_option =
      sub->add_option("--truth", o->truth, "truth.json written by lidarcal simulate");
  auto* reference = sub->add_option("--reference", o->reference,
                                    "REF.json of measured distances or wall-to-wall spans "
                                    "(docs/FORMAT.md, \"Reference measurements\")")
                        ->excludes(truth_option);
  sub->add_option("--model", o->model,
                  "With --reference: also measure with the scans corrected by this model.json")
      ->needs(reference);
  sub->add_option("--inversion", o->inversion,
                  "With --model: ls or ml (see lidarcal correct --help)")
      ->check(CLI::IsMember({"ls", "ml"}))
      ->capture_default_str();
  sub->add_option("--outside", o->outside,
                  "With --model: " + calibration::outsideNames() +
                      " readings beyond the fitted range (see lidarcal correct --help)")
      ->check(CLI::IsMember(calibration::outsidePolicies()))
      ->capture_default_str();
  sub->add_flag("--force", o->force,
                "With --model: apply it to a sequence whose sensor name or range limits differ "
                "from the model's (the same "
                "sensor recorded with other settings)");
  sub->add_option(
         "--radius", o->radius_m,
         "With --reference: pole radius in metres (default: sequence.json, else estimated)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--raw", o->raw,
                  "With --truth: raw sequence (default: the scans/ directory next to truth.json)");
  sub->add_option("-o,--out", o->out, "Also write the JSON to this file");
  sub->callback([o] {
    namespace fs = std::filesystem;
    if (!o->out.empty()) {
      io::checkOutsideInput(o->corrected, o->out);
      io::checkOutputFile(o->out, true);
    }
    if (!o->reference.empty()) return evaluateReference(*o);
    if (o->truth.empty())
      throw InputError("", "--truth", "evaluate needs --truth or --reference", "give one of them");
    const io::SimulationTruth truth = io::loadTruth(o->truth);
    const fs::path raw =
        o->raw.empty() ? fs::path(o->truth).parent_path() / "scans" : fs::path(o->raw);
    const calibration::Evaluation e =
        calibration::evaluate(io::openSequence(o->corrected), io::openSequence(raw), truth);
    const std::string text = evaluationJson(e).dump(2) + "\n";
    std::fputs(text.c_str(), stdout);
    if (!o->out.empty()) io::writeTextAtomically(o->out, text);
  });
}

}  // namespace lidarcal::pipeline
