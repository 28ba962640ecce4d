// lidarcal run [SEQ] --out OUT: the main job. Detect the poles, calibrate, correct every scan,
// and write a report. With no SEQ it runs on the bundled example.

#include <cmath>
#include <cstdio>
#include <future>
#include <memory>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/model_io.hpp"
#include "pipeline/cli_options.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/evaluation_json.hpp"
#include "pipeline/model_text.hpp"
#include "pipeline/papers.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/report.hpp"
#include "pipeline/stages.hpp"
#include "pipeline/ways_forward.hpp"
#include "pipeline/words.hpp"

namespace lidarcal::pipeline {

namespace {

struct RunCommand {
  std::string seq, out = "lidarcal-out", truth, inversion = "ls";
  bool overwrite = false, no_truth = false;
  std::shared_ptr<CalibrationOptions> options = std::make_shared<CalibrationOptions>();
};

void runRun(const RunCommand& c) {
  namespace fs = std::filesystem;
  const fs::path seq_dir = c.seq.empty() ? bundledExample() : fs::path(c.seq);
  if (c.seq.empty() && !quiet()) std::fprintf(stderr, "no sequence given: running on the bundled example %s\n", seq_dir.c_str());
  io::checkOutsideInput(seq_dir, c.out);
  const io::Sequence seq = io::openSequence(seq_dir);
  if (const std::string w = beamCountWarning(seq); !w.empty()) std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
  // Truth: given, or found next to a simulated sequence (DIR/scans + DIR/truth.json).
  fs::path truth_file = c.truth;
  std::error_code ec;
  if (truth_file.empty() && !c.no_truth && fs::exists(seq_dir.parent_path() / "truth.json", ec) &&
      seq_dir.filename() == "scans")
    truth_file = seq_dir.parent_path() / "truth.json";

  io::StagedDirectory out(c.out, c.overwrite);
  const auto config = calibrationConfig(*c.options);
  StageBars progress;
  const SequenceCalibration cal = calibrateSequence(seq, detectionConfig(*c.options), config, std::ref(progress));
  progress.finish();
  if (!cal.model.status.ok())
    throw DataError(seq_dir.string(), "calibration", cal.model.status.name() + std::string(": ") + cal.model.status.message,
                    waysForward(seq, cal.model.status.code));
  io::writeModel(out.path() / "model.json", cal.model);

  const auto method = c.inversion == "ml" ? calibration::InversionMethod::ml : calibration::InversionMethod::ls;
  ReportInputs in;
  in.sequence = seq_dir;
  in.scans = seq.scans.size();
  in.stops = seq.stops.size();
  in.detections = cal.detections.association.assigned;
  in.observations = &cal.observations;
  in.model = &cal.model;
  in.command = "lidarcal run " + (c.seq.empty() ? std::string() : c.seq + " ") + "--out " + c.out;
  if (!truth_file.empty()) {
    Activity activity("evaluate against the truth");
    const SimulationTruth truth = loadTruth(truth_file);
    in.true_landmarks = truth.truth.scene.landmarks;
    auto cf_config = config;
    cf_config.method = calibration::Method::closed_form;
    ComparedModel ours{"lidarcal " + cal.model.method + " (no ground truth)", cal.model, evaluate(cal.model, method, seq, truth)};
    CalibrationModel cf = cal.model.method == "closed-form"
                              ? cal.model
                              : calibration::calibrate(cal.observations, cf_config);
    CalibrationModel bound = calibrateOracle(seq, truth, commandedScale(truth.truth), config);
    CalibrationModel oracle = calibrateOracle(seq, truth, 1.0, config);
    in.compared.push_back(ours);
    if (cal.model.method != "closed-form" && cf.status.ok())
      in.compared.push_back({std::string("closed form of ") + papers::kLandmarks + " (no ground truth)", cf,
                             evaluate(cf, method, seq, truth)});
    in.compared.push_back({"ground truth in the commanded frame (best without ground truth)", bound,
                           evaluate(bound, method, seq, truth)});
    in.compared.push_back({std::string("ground truth (oracle, ") + papers::kTriangulation + " ML)", oracle,
                           evaluate(oracle, method, seq, truth)});
    in.truth_note = "Evaluated on the calibration sequence itself against " + truth_file.string() +
                    " (simulator truth; calibration did not use it). The commanded-frame row fits the true distances "
                    "scaled by the odometry scale error (" + std::to_string(commandedScale(truth.truth)) +
                    "), which no self-calibration can see.";
  }
  // The report (its plots are gnuplot's: a third of the run on 1000 scans) is written while the
  // scans are corrected: the two share only read-only inputs and write into separate folders.
  auto report = std::async(std::launch::async, [&] { writeReport(out.path() / "report", in); });
  fs::create_directory(out.path() / "corrected");
  Progress cprog("correct", seq.scans.size());
  const auto stats = correctSequence(seq, cal.model, method, out.path() / "corrected", io::PcdEncoding::binary,
                                     [&](std::size_t d, std::size_t) { cprog.update(d); }, calibration::kDefaultOutside,
                                     c.options->threads);
  cprog.finish();
  {
    Activity activity("report");
    report.get();
  }
  nlohmann::ordered_json summary{{"sequence", seq_dir.string()},
                                 {"scans", seq.scans.size()},
                                 {"stops", seq.stops.size()},
                                 {"landmarks", cal.detections.association.landmarks.size()},
                                 {"method", cal.model.method},
                                 {"order", cal.model.model.bias.order()},
                                 {"alpha", cal.model.model.bias.alpha},
                                 {"corrected_returns", stats.corrected}};
  if (!in.compared.empty()) summary["evaluation"] = evaluationJson(in.compared.front().evaluation);
  io::writeTextAtomically(out.path() / "summary.json", summary.dump(2) + "\n");
  out.commit();

  std::printf("lidarcal run: %s, %s, %s found\n", plural(seq.scans.size(), "scan").c_str(),
              plural(seq.stops.size(), "stop").c_str(), plural(cal.detections.association.landmarks.size(), "landmark").c_str());
  std::fputs(modelSummary(cal.model).c_str(), stdout);
  if (!in.compared.empty()) {
    const auto& raw = in.compared.front().evaluation.landmarks;
    std::printf("  against the truth, on landmark returns (MSE ratio = raw MSE / corrected MSE: higher is better, 1 = no "
                "gain):\n");
    std::printf("    %-66s RMS %7.1f mm\n", "raw readings:", 1000.0 * std::sqrt(raw.mse_raw_m2));
    for (const auto& m : in.compared)
      std::printf("    %-66s RMS %7.1f mm, MSE ratio %8.2f\n", (m.name + ":").c_str(),
                  1000.0 * std::sqrt(m.evaluation.landmarks.mse_corrected_m2), m.evaluation.landmarks.mse_ratio);
  }
  std::printf("  model:     %s\n  corrected: %s\n  report:    %s\n", (fs::path(c.out) / "model.json").c_str(),
              (fs::path(c.out) / "corrected").c_str(), (fs::path(c.out) / "report/report.md").c_str());
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto c = std::make_shared<RunCommand>();
  CLI::App* sub = app.add_subcommand("run", "The main job: detect, calibrate, correct and report (default: the bundled example)");
  sub->add_option("SEQ", c->seq, "Sequence directory (default: the bundled example)");
  sub->add_option("-o,--out", c->out,
                  "Output directory: model.json, corrected/, report/ (report.md with SVG plots), summary.json")
      ->capture_default_str();
  sub->add_option("--truth", c->truth, "truth.json of a simulated sequence, to evaluate against (found automatically next "
                                       "to DIR/scans)");
  sub->add_flag("--no-truth", c->no_truth, "Do not look for a truth.json next to the sequence");
  sub->add_option("--inversion", c->inversion, "ls or ml (see lidarcal correct --help)")
      ->check(CLI::IsMember({"ls", "ml"}))
      ->capture_default_str();
  sub->add_flag("--overwrite", c->overwrite, "Replace OUT if it exists (needed to run again into the same OUT)");
  addCalibrationOptions(sub, c->options);
  sub->callback([c] { runRun(*c); });
}

}  // namespace lidarcal::pipeline
