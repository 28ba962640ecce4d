// SPDX-License-Identifier: BSD-3-Clause
// lidarcal calibrate SEQ --out model.json [--method closed-form|joint] [--truth truth.json |
// --reference REF.json] [--report DIR]

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "calibration/truth_evaluation.hpp"
#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/model_io.hpp"
#include "io/reference_io.hpp"
#include "pipeline/commands/cli_options.hpp"
#include "pipeline/commands/cmd_rig.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/model_text.hpp"
#include "pipeline/reports/report.hpp"
#include "pipeline/reports/ways_forward.hpp"
#include "pipeline/reports/words.hpp"
#include "pipeline/stages/reference_stage.hpp"
#include "pipeline/stages/stages.hpp"

namespace lidarcal::pipeline {
namespace {

struct CalibrateCommand {
  std::string seq, out, truth, frame = "true", report, reference, reference_fit = "auto";
  bool overwrite = false;
  std::shared_ptr<CalibrationOptions> options = std::make_shared<CalibrationOptions>();
  RigCalibrateSettings rig;  // a rig sequence's own options
};

/// --reference-fit: distances alone (Alhashimi et al. 2016 section 5) or inside the
/// self-calibration. auto: alone when every stop has a measured distance and nothing else is given,
/// combined otherwise (see calibrateWithMeasurements for its fallback).
bool combineWithSelfCalibration(const Reference& ref, std::size_t stops, const std::string& mode) {
  if (mode == "distances") return false;
  if (mode == "combined") return true;
  return measuredStops(ref) != stops || !ref.landmarks.empty() || !ref.stops.empty();
}

/// What stdout shows about the matching of REF.json's entries.
struct MeasurementsShown {
  std::vector<calibration::ReferenceMatch> matches;
  std::string survey;
  SpanReport spans;
};

/// calibrate --reference: what was measured, used as --reference-fit says. Under auto, distances
/// at three or more stops (and nothing else) that the self-calibration cannot use — a sensor
/// that never moved, some of its recordings untaped — are fitted alone. Spans are always fitted
/// with the distances alone (the self-calibration takes none).
SequenceCalibration calibrateWithMeasurements(const CalibrateCommand& c, const io::Sequence& seq,
                                              const calibration::CalibrationConfig& config,
                                              MeasurementsShown& shown) {
  const Reference ref = io::readReference(c.reference);
  io::checkReference(ref, seq.stops.size(), c.reference);
  const auto detection = detectionConfig(*c.options);
  if (!ref.spans.empty() && c.reference_fit == "combined")
    throw InputError(c.reference, "spans",
                     "are fitted with the measured distances alone; the self-calibration "
                     "(--reference-fit combined) "
                     "takes no spans",
                     "use --reference-fit auto or distances, or leave the spans out");
  const bool alone_possible = measuredStops(ref) >= 3 && ref.landmarks.empty() && ref.stops.empty();
  if (ref.spans.empty() && (ref.distances.empty() ||
                            combineWithSelfCalibration(ref, seq.stops.size(), c.reference_fit))) {
    // The self-calibration with the surveyed geometry held fixed and the distances (measured at
    // some stops) in its likelihood.
    StageBars progress;
    std::vector<detectors::SurveyMatch> found;
    const std::filesystem::path ref_file = c.reference;
    const ReferencedSequence r{seq, ref, ref_file, detection, config};
    SequenceCalibration result =
        ref.distances.empty()
            ? calibrateSequenceWithSurvey(r, &found, std::ref(progress))
            : calibrateSequenceWithDistancesAndSelf(r, &shown.matches, &found, std::ref(progress));
    progress.finish();
    const bool fall_back = !result.model.status.ok() && c.reference_fit == "auto" && alone_possible;
    if (!fall_back) {
      shown.survey = surveyTable(found, ref);
      return result;
    }
    std::fprintf(stderr,
                 "lidarcal: the self-calibration cannot use this sequence (%s); fitting the "
                 "distances of the %s "
                 "alone instead (--reference-fit distances)\n",
                 result.model.status.name(), plural(measuredStops(ref), "measured stop").c_str());
    shown.matches.clear();
  }
  // Against the distances (and spans) alone (Alhashimi et al. 2016 section 5).
  if (!ref.landmarks.empty() || !ref.stops.empty())
    std::fprintf(
        stderr,
        "lidarcal: warning: %s: %s fits the measured distances and spans alone: the surveyed "
        "landmarks and measured stops are checked but not used\n",
        c.reference.c_str(),
        ref.spans.empty() ? "--reference-fit distances" : "a REF.json with spans");
  Progress progress("detect", seq.scans.size());
  const std::filesystem::path ref_file = c.reference;
  SequenceCalibration result = calibrateSequenceWithReference(
      ReferencedSequence{seq, ref, ref_file, detection, config}, &shown.matches,
      [&](std::size_t done, std::size_t) { progress.update(done); }, &shown.spans);
  progress.finish();
  return result;
}

void runCalibrate(const CalibrateCommand& c) {
  if (io::isRigDirectory(c.seq)) {
    if (!c.truth.empty() || !c.reference.empty() || !c.report.empty())
      throw InputError(c.seq, "--truth/--reference/--report",
                       "are for one sensor's sequence, not a rig",
                       "calibrate one sensor's directory of the rig with them");
    RigCalibrateSettings rig = c.rig;
    rig.dir = c.seq;
    rig.out = c.out;
    rig.overwrite = c.overwrite;
    rig.options = *c.options;
    return runRigCalibrate(rig);
  }
  io::checkOutsideInput(c.seq, c.out);
  io::checkOutputFile(c.out, c.overwrite);
  if (!c.report.empty()) io::checkOutsideInput(c.seq, c.report);
  const io::Sequence seq = io::openSequence(c.seq);
  if (const std::string w = beamCountWarning(seq); !w.empty())
    std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
  const auto config = calibrationConfig(*c.options);
  // The report directory appears only with the model (staged, committed after model.json).
  std::optional<io::StagedDirectory> report;
  if (!c.report.empty()) report.emplace(c.report, c.overwrite);
  SequenceCalibration result;
  MeasurementsShown shown;
  if (!c.reference.empty()) {
    result = calibrateWithMeasurements(c, seq, config, shown);
  } else if (!c.truth.empty()) {
    // Oracle (Alhashimi et al. 2016): fitted against the true distances; for comparison only.
    const io::SimulationTruth truth = io::loadTruth(c.truth);
    const double scale = c.frame == "commanded" ? calibration::commandedScale(truth.truth) : 1.0;
    result.model = calibration::calibrateOracle(seq, truth, scale, config);
  } else {
    StageBars progress;
    result = calibrateSequence(seq, detectionConfig(*c.options), config, std::ref(progress));
    progress.finish();
  }
  const CalibrationModel& model = result.model;
  if (!model.status.ok())
    throw DataError(c.seq, "calibration",
                    std::string(model.status.name()) + ": " + model.status.message,
                    waysForward(seq, model.status.code));
  if (report) {
    ReportInputs in;
    in.sequence = c.seq;
    in.scans = seq.scans.size();
    in.stops = seq.stops.size();
    in.detections = result.detections.association.assigned;
    in.observations = &result.observations;
    in.model = &model;
    if (!c.reference.empty() && !result.known.empty()) in.known = &result.known;
    in.command =
        "lidarcal calibrate " + c.seq + " --out " + c.out +
        (c.reference.empty() ? " --method " + c.options->method : " --reference " + c.reference);
    writeReport(report->path(), in);
  }
  io::writeModel(c.out, model);
  if (report) report->commit();
  if (!shown.matches.empty()) std::fputs(referenceTable(shown.matches).c_str(), stdout);
  if (!shown.spans.checks.empty())
    std::fputs(spanTable(shown.spans.found, shown.spans.checks).c_str(), stdout);
  if (!shown.survey.empty()) std::fputs(shown.survey.c_str(), stdout);
  std::fputs(modelSummary(model).c_str(), stdout);
  if (!quiet() && model.motion_prior)
    std::fprintf(stderr,
                 "continuous motion: the odometry between consecutive stops entered the joint "
                 "refinement as a "
                 "motion prior (--motion-prior off to tie every stop to its own commanded pose)\n");
  if (!quiet())
    std::fprintf(stderr, "%s model, %s, written to %s\n", model.method.c_str(),
                 orderText(model).c_str(), c.out.c_str());
}

}  // namespace

void addCalibrateCommand(CLI::App& app) {
  auto c = std::make_shared<CalibrateCommand>();
  CLI::App* sub =
      app.add_subcommand("calibrate", "Fit the range model of a sequence (no ground truth needed)");
  sub->add_option("SEQ", c->seq, "Sequence directory (docs/FORMAT.md)")->required();
  sub->add_option("-o,--out", c->out, "model.json to write")->required();
  CLI::Option* truth = sub->add_option("--truth", c->truth,
                                       "truth.json of a simulated sequence: fit against the true "
                                       "distances instead (the oracle, for comparison)");
  sub->add_option("--frame", c->frame,
                  "With --truth: true distances as they are (true), or scaled into the commanded "
                  "frame (commanded): "
                  "the best a self-calibration can reach")
      ->check(CLI::IsMember({"true", "commanded"}))
      ->capture_default_str();
  CLI::Option* reference = sub->add_option("--reference", c->reference,
                                           "REF.json with what you measured (docs/FORMAT.md, "
                                           "\"Reference measurements\"): distances (tape, "
                                           "laser meter) and wall-to-wall spans (a laser meter "
                                           "across the room between two walls the sensor "
                                           "sees) fit the range model to them (Alhashimi et al. "
                                           "2016, section 5); without distances or spans, "
                                           "surveyed landmark centres and measured stop poses are "
                                           "held fixed in the self-calibration")
                               ->excludes(truth);
  sub->add_option("--reference-fit", c->reference_fit,
                  "With --reference distances: distances (fit the range model to them alone; every "
                  "measured stop "
                  "counts), combined (add them to the self-calibration of the whole sequence, with "
                  "the surveyed "
                  "landmarks and stops held fixed), or auto: distances when every stop has one and "
                  "no landmarks or "
                  "stops are given, combined otherwise, and distances after all when the "
                  "self-calibration cannot use "
                  "the sequence (a sensor that never moved) and 3 or more stops have one. Spans "
                  "are always fitted "
                  "with the distances alone")
      ->check(CLI::IsMember({"auto", "distances", "combined"}))
      ->capture_default_str()
      ->needs(reference);
  sub->add_option("--report", c->report,
                  "Also write a report (report.md with SVG plots, and the .dat/.gp files that draw "
                  "them) into this new "
                  "directory (not with --truth)")
      ->excludes(truth);
  sub->add_flag("--overwrite", c->overwrite, "Replace --out if it exists");
  addCalibrationOptions(sub, c->options);
  sub->add_option("--rig-frame", c->rig.frame,
                  "Rig sequence: the frame of the mountings: vehicle (needs recorded poses and a "
                  "turn), relative (the "
                  "reference sensor held at its tf_static design) or auto")
      ->check(CLI::IsMember({"auto", "vehicle", "relative"}))
      ->capture_default_str();
  sub->add_option("--reference-sensor", c->rig.reference,
                  "Rig sequence: the reference sensor (default: the first)");
  sub->add_option("--min-intensity", c->rig.min_intensity,
                  "Rig sequence: points returning less intensity read as no return "
                  "(retro-reflective poles stand out; "
                  "0: off)")
      ->capture_default_str();
  sub->add_option("--associate", c->rig.associate_m,
                  "Rig sequence: a detection within this many metres of a pole (designed "
                  "mountings, vehicle poses) is "
                  "that pole")
      ->capture_default_str();
  sub->callback([c] { runCalibrate(*c); });
}

}  // namespace lidarcal::pipeline
