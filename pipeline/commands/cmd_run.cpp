// SPDX-License-Identifier: BSD-3-Clause
// lidarcal run [SEQ] --out OUT: the main job. Detect the poles, calibrate, correct every scan,
// and write a report. With no SEQ it runs on the bundled example.

#include <cmath>
#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/model_io.hpp"
#include "io/output_files.hpp"
#include "pipeline/commands/cli_options.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/evaluation_json.hpp"
#include "pipeline/reports/model_text.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/reports/report.hpp"
#include "pipeline/reports/ways_forward.hpp"
#include "pipeline/reports/words.hpp"
#include "pipeline/stages/stages.hpp"
#include "pipeline/stages/truth_stage.hpp"

namespace lidarcal::pipeline {

namespace {

struct RunCommand {
  std::string seq, out = "lidarcal-out", truth;
  bool overwrite = false, no_truth = false;
  std::shared_ptr<CalibrationOptions> options = std::make_shared<CalibrationOptions>();
  std::shared_ptr<CorrectionOptions> correction = std::make_shared<CorrectionOptions>();
};

/// The run in a few lines on stdout.
void printRun(const RunCommand& c, const io::Sequence& seq, const SequenceCalibration& cal,
              const ReportInputs& in, const CorrectionStats& stats, calibration::Outside outside) {
  namespace fs = std::filesystem;
  std::printf("lidarcal run: %s, %s, %s found\n", plural(seq.scans.size(), "scan").c_str(),
              plural(seq.stops.size(), "stop").c_str(),
              plural(cal.detections.association.landmarks.size(), "landmark").c_str());
  std::fputs(modelSummary(cal.model).c_str(), stdout);
  std::printf(
      "  corrected scans: %zu returns inside the fitted range, %zu beyond it, %zu without a "
      "distance\n",
      stats.corrected, stats.extrapolated, stats.unresolved);
  if (const std::string beyond = beyondFitText(stats, cal.model, outside); !beyond.empty())
    std::printf("  %s\n", beyond.c_str());
  if (!in.compared.empty()) {
    const calibration::Evaluation& ours = in.compared.front().evaluation;
    std::printf(
        "  against the truth (MSE ratio = raw MSE / corrected MSE: higher is better, 1 = no "
        "gain):\n");
    std::printf("    %-62s %12s %12s\n", "", "landmarks", "all returns");
    std::printf("    %-62s %9.1f mm %9.1f mm\n",
                "raw readings, RMS:", 1000.0 * std::sqrt(ours.landmarks.mse_raw_m2),
                1000.0 * std::sqrt(ours.all.mse_raw_m2));
    std::printf("    %-62s %9.1f mm %9.1f mm\n", "corrected readings (the written scans), RMS:",
                1000.0 * std::sqrt(ours.landmarks.mse_corrected_m2),
                1000.0 * std::sqrt(ours.all.mse_corrected_m2));
    for (const auto& m : in.compared)
      std::printf("    %-62s %12.2f %12.2f\n", (m.name + ", MSE ratio:").c_str(),
                  m.evaluation.landmarks.mse_ratio, m.evaluation.all.mse_ratio);
  }
  std::printf("  model:     %s\n  corrected: %s\n  report:    %s\n",
              (fs::path(c.out) / "model.json").c_str(), (fs::path(c.out) / "corrected").c_str(),
              (fs::path(c.out) / "report/report.md").c_str());
}

/// The truth to evaluate against: --truth, or found next to a simulated sequence (DIR/scans +
/// DIR/truth.json) unless --no-truth; empty when there is none.
std::filesystem::path truthFile(const RunCommand& c, const std::filesystem::path& seq_dir) {
  namespace fs = std::filesystem;
  fs::path truth_file = c.truth;
  std::error_code ec;
  if (truth_file.empty() && !c.no_truth && fs::exists(seq_dir.parent_path() / "truth.json", ec) &&
      seq_dir.filename() == "scans")
    truth_file = seq_dir.parent_path() / "truth.json";
  return truth_file;
}

/// summary.json: the sequence, the model, the corrected returns and, with truth, the evaluations.
nlohmann::ordered_json runSummary(const std::filesystem::path& seq_dir, const io::Sequence& seq,
                                  const SequenceCalibration& cal, const ReportInputs& in,
                                  const CorrectionStats& stats, calibration::Outside outside) {
  nlohmann::ordered_json summary{{"sequence", seq_dir.string()},
                                 {"scans", seq.scans.size()},
                                 {"stops", seq.stops.size()},
                                 {"landmarks", cal.detections.association.landmarks.size()},
                                 {"method", cal.model.method},
                                 {"order", cal.model.model.bias.order()},
                                 {"alpha", cal.model.model.bias.alpha},
                                 {"outside", calibration::toString(outside)},
                                 {"corrected_returns", stats.corrected},
                                 {"extrapolated_returns", stats.extrapolated},
                                 {"beyond_fitted_range_returns", stats.beyond()},
                                 {"unresolved_returns", stats.unresolved}};
  if (!in.compared.empty()) {
    summary["evaluation"] = evaluationJson(in.compared.front().evaluation);
    auto baselines = nlohmann::ordered_json::array();
    for (std::size_t k = 1; k < in.compared.size(); ++k)
      baselines.push_back({{"model", in.compared[k].name},
                           {"order", in.compared[k].model.model.bias.order()},
                           {"evaluation", evaluationJson(in.compared[k].evaluation)}});
    summary["baselines"] = baselines;
  }
  return summary;
}

void runRun(const RunCommand& c) {
  namespace fs = std::filesystem;
  const fs::path seq_dir = c.seq.empty() ? bundledExample() : fs::path(c.seq);
  if (c.seq.empty() && !quiet())
    std::fprintf(stderr, "no sequence given: running on the bundled example %s\n", seq_dir.c_str());
  io::checkOutsideInput(seq_dir, c.out);
  const io::Sequence seq = io::openSequence(seq_dir);
  if (const std::string w = beamCountWarning(seq); !w.empty())
    std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
  const fs::path truth_file = truthFile(c, seq_dir);

  io::StagedDirectory out(c.out, c.overwrite);
  const auto config = calibrationConfig(*c.options);
  StageBars progress;
  const SequenceCalibration cal =
      calibrateSequence(seq, detectionConfig(*c.options), config, std::ref(progress));
  progress.finish();
  if (!cal.model.status.ok())
    throw DataError(seq_dir.string(), "calibration",
                    cal.model.status.name() + std::string(": ") + cal.model.status.message,
                    waysForward(seq, cal.model.status.code));
  io::writeModel(out.path() / "model.json", cal.model);

  const calibration::InversionMethod method = c.correction->method();
  const calibration::Outside outside = c.correction->outsidePolicy();
  io::makeDirectory(out.path() / "corrected");
  Progress cprog("correct", seq.scans.size());
  const SequenceCorrection how{method, outside, io::PcdEncoding::binary, c.options->threads};
  const auto stats = correctSequence(seq, cal.model, out.path() / "corrected", how,
                                     [&](std::size_t d, std::size_t) { cprog.update(d); });
  cprog.finish();

  ReportInputs in;
  in.sequence = seq_dir;
  in.scans = seq.scans.size();
  in.stops = seq.stops.size();
  in.detections = cal.detections.association.assigned;
  in.observations = &cal.observations;
  in.model = &cal.model;
  in.correction = &stats;
  in.outside = outside;
  in.command = "lidarcal run " + (c.seq.empty() ? std::string() : c.seq + " ") + "--out " + c.out;
  if (!truth_file.empty()) {
    Activity activity("evaluate against the truth");
    const io::SimulationTruth truth = io::loadTruth(truth_file);
    in.true_landmarks = truth.truth.scene.landmarks;
    in.compared = compareWithTruth(seq, out.path() / "corrected", truth, cal, config, how);
    in.truth_note = "Evaluated on the calibration sequence itself against " + truth_file.string() +
                    " (simulator truth; calibration did not use it). Our row scores the corrected "
                    "scans as written "
                    "in corrected/, read back; the other rows apply their models under the same "
                    "rule (--outside " +
                    calibration::toString(outside) + ").";
  }
  {
    Activity activity("report");
    writeReport(out.path() / "report", in);
  }
  io::writeTextAtomically(out.path() / "summary.json",
                          runSummary(seq_dir, seq, cal, in, stats, outside).dump(2) + "\n");
  out.commit();
  printRun(c, seq, cal, in, stats, outside);
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto c = std::make_shared<RunCommand>();
  CLI::App* sub = app.add_subcommand(
      "run", "The main job: detect, calibrate, correct and report (default: the bundled example)");
  sub->add_option("SEQ", c->seq, "Sequence directory (default: the bundled example)");
  sub->add_option("-o,--out", c->out,
                  "Output directory: model.json, corrected/, report/ (report.md with SVG plots), "
                  "summary.json")
      ->capture_default_str();
  sub->add_option(
      "--truth", c->truth,
      "truth.json of a simulated sequence, to evaluate against (found automatically next "
      "to DIR/scans)");
  sub->add_flag("--no-truth", c->no_truth, "Do not look for a truth.json next to the sequence");
  addCorrectionOptions(sub, c->correction);
  sub->add_flag("--overwrite", c->overwrite,
                "Replace OUT if it exists (needed to run again into the same OUT)");
  addCalibrationOptions(sub, c->options);
  sub->callback([c] { runRun(*c); });
}

}  // namespace lidarcal::pipeline
