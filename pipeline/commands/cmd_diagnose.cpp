// SPDX-License-Identifier: BSD-3-Clause
// lidarcal diagnose DATA --out DIR [--model model.json] [--seed S] [--mode auto|sequence|static]
// Model criticism: what the seeds' model gets wrong on the data, the named cause, the extended
// model and its held-out gain (diagnosis/diagnosis.hpp). Writes DIR/diagnosis.json, report.md
// and plots (docs/FORMAT.md).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>

#include <glog/logging.h>
#include <CLI/CLI.hpp>

#include "calibration/inversion.hpp"
#include "common/errors.hpp"
#include "detectors/sightings.hpp"
#include "diagnosis/sequence.hpp"
#include "diagnosis/static_scene.hpp"
#include "diagnosis/windows.hpp"
#include "io/atomic_file.hpp"
#include "io/model_io.hpp"
#include "io/simulation_truth.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/diagnose_report.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {
namespace {

struct DiagnoseCommand {
  std::string data, out, model, mode = "auto", truth, candidates;
  std::uint64_t seed = 1;
  int replicas = 19, folds = 3, stop = -1;
  std::size_t max_readings = 10000;
  double alpha = 0.01, radius_m = 0.0, sigma_s_m = 0.02, range_offset_m = std::nan("");
  bool overwrite = false;
  std::string command;
};

diagnosis::DiagnoseConfig diagnoseConfig(const DiagnoseCommand& c) {
  diagnosis::DiagnoseConfig config;
  config.seed = c.seed;
  config.replicas = c.replicas;
  config.folds = c.folds;
  config.alpha = c.alpha;
  config.sigma_s_m = c.sigma_s_m;
  config.static_range_offset_m = c.range_offset_m;
  if (!c.candidates.empty()) {
    std::stringstream ss(c.candidates);
    std::string item;
    while (std::getline(ss, item, ',')) {
      if (item.empty()) continue;
      const std::optional<Effect> e = parseEffect(item);
      if (!e)
        throw InputError("", "--candidates", "unknown effect '" + item + "'",
                         "use " + effectNames([](const EffectInfo& i) {
                           return i.sequence_statistic || i.static_statistic;
                         }));
      config.candidates.push_back(*e);
    }
  }
  return config;
}

/// The model's inverse when --model is given (else readings pass unchanged).
diagnosis::ReadingCorrection makeCorrector(const std::string& model) {
  diagnosis::ReadingCorrection fix;
  if (model.empty()) return fix;
  const CalibrationModel m = io::readModel(model);
  try {
    fix.inverter.emplace(m.model,
                         calibration::inversionWindow(m.model, calibration::InversionMethod::ls));
  } catch (const std::invalid_argument& e) {
    throw DataError(model, "bias.alpha", std::string("cannot be inverted: ") + e.what(),
                    "calibrate again");
  }
  return fix;
}

/// Mode: a sequence with landmarks seen from several stops (the landmarks' observations), else
/// none (repeated scans of one stop).
std::optional<LandmarkObservations> findLandmarks(const DiagnoseCommand& c,
                                                  const io::Sequence& seq) {
  std::optional<LandmarkObservations> obs;
  if (c.mode == "static" || seq.stops.size() < 2) {
    if (c.mode == "sequence")
      throw DataError(c.data, "stops", "a sequence diagnosis needs scans from at least two stops",
                      "diagnose repeated scans of one pose with --mode static");
    return obs;
  }
  detectors::SequenceDetectionConfig dc;
  if (c.radius_m > 0.0) dc.detection.landmark_radius_m = c.radius_m;
  Progress progress("detect", seq.scans.size());
  const auto det = detectors::detectSequence(
      seq, dc, [&](std::size_t d, std::size_t t) { progress.update(d, t); });
  progress.finish();
  if (!det.association.landmarks.empty()) {
    // The beams beside each pole that read between it and the background: mixed pixels' readings.
    obs = detectors::toLandmarkObservations(seq, det, detectors::SightingOptions{true});
    if (!seq.meta.range_max_m) {
      double max_reading = 0.0;
      for (const auto& s : obs->sightings)
        for (const auto& b : s.beams) max_reading = std::max(max_reading, b.range_m);
      obs->range_max_m = max_reading > 0.0 ? 1.25 * max_reading : 1.0;
    }
  } else if (c.mode == "sequence") {
    throw DataError(
        c.data, "landmarks", "no landmark was found in the sequence: " + det.note,
        "give the radius with --radius, or diagnose repeated scans of one pose with --mode static");
  }
  return obs;
}

void checkCandidates(const diagnosis::DiagnoseConfig& config, const std::vector<Effect>& known,
                     const char* kind) {
  for (Effect e : config.candidates)
    if (std::find(known.begin(), known.end(), e) == known.end()) {
      std::string list;
      for (Effect k : known) list += (list.empty() ? "" : ", ") + std::string(toString(k));
      throw InputError("", "--candidates",
                       std::string("'") + toString(e) + "' is not a candidate effect for " + kind,
                       "use " + list);
    }
}

/// True range of every beam of every sighting from truth.json (NaN where the truth has none).
std::vector<std::vector<double>> truthRanges(const std::string& path,
                                             const LandmarkObservations& obs) {
  const io::SimulationTruth truth = io::loadTruth(path);
  std::vector<std::vector<double>> ranges;
  for (const auto& s : obs.sightings) {
    std::vector<double> t;
    for (const auto& b : s.beams)
      t.push_back(s.scan * truth.beams + b.beam < truth.ranges.size()
                      ? truth.at(s.scan, b.beam).range_m
                      : std::nan(""));
    ranges.push_back(std::move(t));
  }
  return ranges;
}

diagnosis::DiagnosisResult diagnoseLandmarks(const DiagnoseCommand& c,
                                             const diagnosis::DiagnoseConfig& config,
                                             const diagnosis::ReadingCorrection& fix,
                                             LandmarkObservations& obs, DiagnosisSource& src) {
  checkCandidates(
      config,
      diagnosis::candidateList(diagnosis::DiagnoseConfig{}, diagnosis::DiagnoseMode::sequence),
      "a sequence");
  src.selection = diagnosis::leadingWindow(obs, c.max_readings);
  if (!src.selection.empty() && !quiet())
    std::fprintf(stderr, "a long sequence: diagnosing %s; --max-readings 0 takes them all\n",
                 src.selection.c_str());
  diagnosis::correctReadings(obs, fix);
  for (const auto& s : obs.sightings)
    src.beside_pole_readings += static_cast<std::size_t>(std::count_if(
        s.beams.begin(), s.beams.end(), [](const BeamReading& b) { return b.beside; }));
  std::vector<std::vector<double>> truth_ranges;
  if (!c.truth.empty()) truth_ranges = truthRanges(c.truth, obs);
  if (!quiet())
    std::fprintf(stderr, "diagnosing a sequence: %s (%s)\n",
                 plural(obs.sightings.size(), "sighting").c_str(),
                 plural(static_cast<std::size_t>(c.replicas), "replica").c_str());
  diagnosis::DiagnosisResult result =
      diagnosis::diagnoseSequence(obs, config, c.truth.empty() ? nullptr : &truth_ranges);
  return result;
}

/// Static mode: --stop, else the stop with the most scans.
std::size_t pickStop(const DiagnoseCommand& c, const io::Sequence& seq) {
  if (c.stop >= 0) {
    if (static_cast<std::size_t>(c.stop) >= seq.stops.size())
      throw InputError(c.data, "--stop", "the sequence has " + plural(seq.stops.size(), "stop"),
                       "give a stop index from 0");
    return static_cast<std::size_t>(c.stop);
  }
  return diagnosis::busiestStop(seq);
}

diagnosis::DiagnosisResult diagnoseOnePose(const DiagnoseCommand& c, const io::Sequence& seq,
                                           const diagnosis::DiagnoseConfig& config,
                                           const diagnosis::ReadingCorrection& fix,
                                           DiagnosisSource& src) {
  const std::size_t stop = pickStop(c, seq);
  if (seq.stops.size() > 1)
    src.selection += "stop " + std::to_string(stop) + " of " + std::to_string(seq.stops.size()) +
                     ", " + plural(seq.stops[stop].scans.size(), "scan") + " from one pose";
  checkCandidates(
      config,
      diagnosis::candidateList(diagnosis::DiagnoseConfig{}, diagnosis::DiagnoseMode::static_scene),
      "repeated scans of one pose");
  Progress reading("read the scans of stop " + std::to_string(stop), seq.stops[stop].scans.size());
  const diagnosis::StaticScans s =
      diagnosis::staticScans(seq, stop, fix, [&](std::size_t done) { reading.update(done); });
  reading.finish();
  if (!quiet())
    std::fprintf(stderr, "diagnosing repeated scans of one pose: %s, %s (%s)\n",
                 plural(s.scans, "scan").c_str(), plural(s.readings.size(), "reading").c_str(),
                 plural(static_cast<std::size_t>(c.replicas), "replica").c_str());
  diagnosis::DiagnosisResult result = diagnosis::diagnoseStatic(s, config, &src.walls);
  return result;
}

void runDiagnose(const DiagnoseCommand& c) {
  namespace fs = std::filesystem;
  // Ceres reports (through glog) the linear-solver failures its Levenberg-Marquardt steps recover
  // from by themselves; the many fits of a diagnosis would fill the terminal with them.
  FLAGS_minloglevel = google::GLOG_ERROR;
  io::checkOutsideInput(c.data, c.out);
  const io::Sequence seq = io::openSequence(c.data);
  diagnosis::DiagnoseConfig config = diagnoseConfig(c);
  // a bar per step on a terminal (a forklift's 1081-beam static recording takes a while)
  StageBars bars;
  config.progress = std::ref(bars);
  const diagnosis::ReadingCorrection fix = makeCorrector(c.model);
  io::StagedDirectory out(c.out, c.overwrite);
  DiagnosisSource src;
  src.data = c.data;
  src.sensor = seq.meta.sensor_name.value_or("");
  src.model = c.model;
  src.command = c.command;
  std::optional<LandmarkObservations> obs = findLandmarks(c, seq);
  diagnosis::DiagnosisResult result;
  if (obs && c.mode != "static") {
    result = diagnoseLandmarks(c, config, fix, *obs, src);
    if (!result.status.ok() && c.mode == "auto") {
      // Poles were found but cannot carry a sequence diagnosis: look at one pose instead.
      bars.finish();
      if (!quiet())
        std::fprintf(stderr,
                     "the sequence cannot be diagnosed (%s: %s); diagnosing repeated scans of one "
                     "pose instead\n",
                     result.status.name(), result.status.message.c_str());
      src.selection = "sequence diagnosis failed (" + std::string(result.status.name()) + "), ";
      obs.reset();
    }
  }
  if (!obs || c.mode == "static") result = diagnoseOnePose(c, seq, config, fix, src);
  bars.finish();
  writeDiagnosis(out.path(), result, src);
  out.commit();
  if (!result.status.ok())
    throw DataError(c.data, "diagnosis",
                    std::string(result.status.name()) + ": " + result.status.message,
                    "see " + (fs::path(c.out) / "report.md").string());
  if (!quiet())
    std::fprintf(stderr, "%s: primary cause %s; report in %s\n", toString(result.mode),
                 result.primary_cause.c_str(), (fs::path(c.out) / "report.md").c_str());
  std::printf("%s\n", result.primary_cause.c_str());
}

}  // namespace

void addDiagnoseCommand(CLI::App& app) {
  auto c = std::make_shared<DiagnoseCommand>();
  CLI::App* sub =
      app.add_subcommand("diagnose",
                         "Show what the published range model gets wrong on measured data, name "
                         "the cause, fit the extended model, measure the gain");
  sub->add_option("DATA", c->data,
                  "Sequence directory (docs/FORMAT.md): scans of poles from several stops, or "
                  "repeated scans from one pose")
      ->required();
  sub->add_option("-o,--out", c->out,
                  "Output directory: diagnosis.json, report.md with PNG plots (and the "
                  ".dat/plots.gp files that draw them)")
      ->required();
  sub->add_option("--model", c->model,
                  "Diagnose the readings corrected with this model.json (what the calibrated model "
                  "still gets wrong)");
  sub->add_option("--seed", c->seed,
                  "Seed of the bootstrap replicas; the same data and seed give the same output")
      ->capture_default_str();
  sub->add_option("--mode", c->mode,
                  "auto: a sequence when poles are found at two stops or more, else static")
      ->check(CLI::IsMember({"auto", "sequence", "static"}))
      ->capture_default_str();
  sub->add_option("--replicas", c->replicas, "Parametric bootstrap replicas")
      ->check(CLI::Range(5, 1000))
      ->capture_default_str();
  sub->add_option("--folds", c->folds, "Cross-validation folds (by scan)")
      ->check(CLI::Range(2, 20))
      ->capture_default_str();
  sub->add_option("--alpha", c->alpha, "Family-wise error rate over the candidates (Holm)")
      ->check(CLI::Range(1e-6, 0.5))
      ->capture_default_str();
  sub->add_option("--candidates", c->candidates,
                  "Comma-separated effects to test (default: all of the mode)");
  sub->add_option(
      "--truth", c->truth,
      "truth.json of a simulated sequence: also measure the gain in calibration (MSE ratio)");
  sub->add_option("--max-readings", c->max_readings,
                  "Sequence mode: diagnose the leading stops that hold at most this many landmark "
                  "readings (0: all; a "
                  "diagnosis refits the whole problem for every replica, candidate and fold)")
      ->capture_default_str();
  sub->add_option("--stop", c->stop,
                  "Static mode: the stop to use (default: the one with the most scans)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--radius", c->radius_m,
                  "Landmark radius in metres (default: sequence.json, else estimated)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--sigma-s", c->sigma_s_m,
                  "Odometry: std. dev. of a stop's position around the commanded one (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--range-offset", c->range_offset_m,
                  "Static mode: the range offset alpha_0 (m) when known from a reference distance, "
                  "instead of the walls' "
                  "straightness");
  sub->add_flag("--overwrite", c->overwrite, "Replace --out if it exists");
  sub->callback([c, sub] {
    c->command = "lidarcal diagnose " + c->data + " --out " + c->out;
    for (const auto* o : sub->get_options())
      if (o->count() > 0 && !o->get_lnames().empty() && o->get_lnames().front() != "out" &&
          o->get_lnames().front() != "help") {
        c->command += " --" + o->get_lnames().front();
        if (o->get_expected_max() != 0) c->command += " " + o->as<std::string>();
      }
    runDiagnose(*c);
  });
}

}  // namespace lidarcal::pipeline
