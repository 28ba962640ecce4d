// SPDX-License-Identifier: BSD-3-Clause
// lidarcal detect SEQ --out OUT: landmarks in every scan, one id per landmark over the sequence.
// Writes OUT/ (labelled copies of the scans, sequence.json, landmarks.csv); prints a summary.
// Two passes over the files: detect + associate (the scans of one stop in memory at a time), then
// labels (each stop detected again: memory does not grow with the number of scans).

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "detectors/evaluation.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/atomic_file.hpp"
#include "io/landmarks_csv.hpp"
#include "io/output_files.hpp"
#include "io/scene_io.hpp"
#include "io/sequence.hpp"
#include "io/true_ranges.hpp"
#include "pipeline/commands/cli_options.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {
namespace {

namespace fs = std::filesystem;

struct DetectOptions {
  std::string seq;
  std::string out;
  bool overwrite = false;
  bool ascii = false;
  double radius_m = 0.0;  // 0: sequence.json or estimated
  bool estimate_radius = false;
  int min_stops = 3;
  double link_distance_m = 0.35;
  int max_missing_beams = 1;
  std::vector<double> inlier_threshold{0.01, 0.005};  // A, B of t(r) = A + B r^2
  std::string truth;
  int threads = 0;  // 0: automatic
};

void printEvaluation(const detectors::DetectionEvaluation& ev) {
  std::printf("\n## Evaluation against the truth\n\n");
  std::printf(
      "| detections | true positives | false positives | precision | observable | detected | "
      "recall | purity | wrong ids | split ids |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  std::printf("| %zu | %zu | %zu | %.4f | %zu | %zu | %.4f | %.4f | %zu | %zu |\n", ev.detections,
              ev.true_positives, ev.false_positives, ev.precision, ev.observable, ev.detected,
              ev.recall, ev.purity, ev.wrong_id, ev.split_ids);
  std::printf(
      "\n| true range (m) | observable | detected | centre RMS (m) | bearing RMS (mrad) | range - "
      "(f(D-R)+R) mean (m) | free radius error mean (m) | free radius RMS (m) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const auto& b : ev.bins)
    if (b.observable || b.detections)
      std::printf("| %.0f-%.0f | %zu | %zu | %.4f | %.2f | %+.4f | %+.4f | %.4f |\n", b.lo_m,
                  b.hi_m, b.observable, b.detected, b.centre_rms_m, b.bearing_rms_rad * 1e3,
                  b.range_bias_m, b.free_radius_bias_m, b.free_radius_rms_m);
}

/// The detection settings of the command's options; throws InputError for a threshold A <= 0.
detectors::SequenceDetectionConfig detectionSettings(const DetectOptions& o) {
  detectors::SequenceDetectionConfig cfg;
  if (o.radius_m > 0.0) cfg.detection.landmark_radius_m = o.radius_m;
  cfg.use_sequence_radius = !o.estimate_radius;
  cfg.association.min_stops = o.min_stops;
  cfg.association.link_distance_m = o.link_distance_m;
  cfg.detection.segmentation.max_missing_beams = o.max_missing_beams;
  applyInlierThreshold(o.inlier_threshold, cfg.detection);
  cfg.association.min_link_distance_m =
      std::min(cfg.association.min_link_distance_m, o.link_distance_m);
  // The evaluation against the truth needs every scan's detections at once; otherwise nothing
  // per scan is kept in memory and the labelling pass reads the detections back from a
  // temporary file (detectors/detection_log.hpp).
  cfg.keep_scans = !o.truth.empty();
  cfg.threads = o.threads;
  return cfg;
}

/// The simulator's truth and its true ranges by scan (none without --truth).
struct DetectTruth {
  std::optional<Truth> truth;
  std::map<std::size_t, std::vector<io::TrueRange>> ranges;
};

DetectTruth readDetectTruth(const DetectOptions& o) {
  DetectTruth t;
  if (o.truth.empty()) return t;
  t.truth = io::readTruth(o.truth);
  for (auto& r : io::readTrueRanges(fs::path(o.truth).parent_path() / t.truth->true_ranges_file))
    t.ranges[r.scan].push_back(r);
  return t;
}

/// Second pass: the same points in the same order, with a label per point, into `out_dir`, with
/// landmarks.csv and sequence.json; the scans' truth when there is one.
std::vector<detectors::ScanTruth> writeLabelledScans(const DetectOptions& o,
                                                     const io::Sequence& seq,
                                                     const detectors::SequenceDetections& result,
                                                     DetectTruth& t, const fs::path& out_dir) {
  std::optional<Truth>& truth = t.truth;
  std::map<std::size_t, std::vector<io::TrueRange>>& true_ranges = t.ranges;
  const fs::path meta = seq.dir / "sequence.json";
  if (fs::exists(meta)) io::copyFile(meta, out_dir / "sequence.json");
  io::LandmarksCsvWriter csv(out_dir / "landmarks.csv");
  std::vector<detectors::ScanTruth> scan_truth;
  Progress progress("label", seq.scans.size());
  auto write = [&](std::size_t i, const io::Scan& loaded, const detectors::ScanDetections& sd,
                   const std::vector<int>& ids) {
    io::Scan scan = loaded;
    scan.labels = detectors::scanLabels(sd, ids, scan.cloud->size());
    const std::string name = seq.scans[i].name();
    io::writeScan(out_dir / name, scan, o.ascii ? io::PcdEncoding::ascii : io::PcdEncoding::binary);
    const auto& dets = sd.detections;
    for (std::size_t j = 0; j < dets.size(); ++j) {
      const int id = ids[j];
      if (id == 0) continue;
      const auto& d = dets[j];
      csv.write(io::LandmarkRow{name, seq.stopOf(i), id, d.bearing_rad, d.range_m, d.centre_x_m,
                                d.centre_y_m, d.radius_m, d.inliers.size(), d.rms_m});
    }
    if (truth) {
      auto it = true_ranges.find(i);
      if (it == true_ranges.end())
        throw InputError(o.truth, "scan " + std::to_string(i), "has no rows in the true ranges",
                         "pass the truth.json written with this sequence");
      scan_truth.push_back(detectors::makeScanTruth(*truth, i, std::move(it->second), *scan.cloud));
    }
  };
  detectors::forEachLoadedScan(result, seq, write,
                               [&](std::size_t done, std::size_t) { progress.update(done); });
  progress.finish();
  csv.close();
  return scan_truth;
}

/// The landmarks found, as Markdown on stdout.
void printDetectSummary(const DetectOptions& o, const io::Sequence& seq,
                        const detectors::SequenceDetections& result,
                        const detectors::SequenceDetectionConfig& cfg) {
  const auto& a = result.association;
  const std::size_t circles = a.detections;
  std::printf("# Landmarks of %s\n\n", o.seq.c_str());
  std::printf("- scans: %s at %s\n", plural(seq.scans.size(), "scan").c_str(),
              plural(seq.stops.size(), "stop").c_str());
  if (result.continuous)
    std::printf(
        "- continuous motion (nearly every scan its own pose): a landmark's reach grows by %.2f m "
        "per metre "
        "travelled since it was last seen, up to %.2f m\n",
        cfg.continuous_drift_per_m,
        std::max(cfg.association.max_link_distance_m, cfg.association.link_distance_m));
  switch (result.radius_source) {
    case detectors::RadiusSource::known:
      std::printf("- radius: given (%.4f m)", result.known_radius_m.value_or(0.0));
      break;
    case detectors::RadiusSource::estimated:
      std::printf("- radius: estimated from the data");
      if (result.common_radius_m)
        std::printf(" (common to all landmarks: %.4f m)", *result.common_radius_m);
      break;
    case detectors::RadiusSource::none:
      std::printf("- radius: unknown (no landmark to estimate it from)");
      break;
  }
  // The association wants a landmark at min_stops stops, capped at the stops there are: on a
  // recording with fewer, say what the discards mean there and what it cannot do.
  const std::size_t stops = seq.stops.size(), wanted = static_cast<std::size_t>(o.min_stops);
  const std::size_t capped = std::min(stops, wanted);
  const std::string why = capped <= 1
                              ? "found in fewer than half the scans of the stop"
                              : "found in half the scans of fewer than " + plural(capped, "stop");
  std::printf(
      "\n- circle detections: %zu, given a landmark id: %zu (discarded: %zu %s, %zu in conflict)\n",
      circles, a.assigned, a.discarded_few_stops, why.c_str(), a.discarded_conflicts);
  if (stops < wanted)
    std::printf(
        "- the association follows a landmark over %s (--min-stops) and this recording has %s, so "
        "a circle %s "
        "counts; triangulating the landmarks (calibrate, run) needs %s: record more, or calibrate "
        "against "
        "measured distances or wall-to-wall spans (calibrate --reference, docs/FORMAT.md)\n",
        plural(wanted, "stop").c_str(), plural(stops, "stop").c_str(),
        stops == 1 ? "found in half of its scans" : "found in half the scans of all of them",
        plural(wanted, "stop").c_str());
  std::printf("- %s\n", result.note.c_str());
  if (!a.landmarks.empty()) {
    std::printf(
        "\n| id | x_m (world) | y_m (world) | radius_m | detections | stops | first scan "
        "|\n|---|---|---|---|---|---|---|\n");
    for (const auto& l : a.landmarks)
      std::printf("| %d | %.3f | %.3f | %.4f%s | %zu | %zu | %zu |\n", l.id, l.x_m, l.y_m,
                  l.radius_m, l.radius_estimated ? " (estimated)" : "", l.detections, l.stops,
                  l.first_scan);
  }
  std::printf("\nOutput: %s (labelled scans, sequence.json, landmarks.csv)\n", o.out.c_str());
}

void runDetect(const DetectOptions& o) {
  const io::Sequence seq = io::openSequence(o.seq);
  io::checkOutsideInput(o.seq, o.out);
  const detectors::SequenceDetectionConfig cfg = detectionSettings(o);
  DetectTruth truth = readDetectTruth(o);

  io::StagedDirectory out(o.out, o.overwrite);
  detectors::SequenceDetections result;
  {
    std::unique_ptr<Progress> progress;
    result = detectors::detectSequence(seq, cfg, [&](std::size_t done, std::size_t total) {
      if (!progress) progress = std::make_unique<Progress>("detect", total);
      progress->update(done, total);
    });
    if (progress) progress->finish();
  }
  const std::vector<detectors::ScanTruth> scan_truth =
      writeLabelledScans(o, seq, result, truth, out.path());
  out.commit();
  printDetectSummary(o, seq, result, cfg);
  if (truth.truth)
    printEvaluation(
        detectors::evaluateDetections(result.scans, &result.association, scan_truth, *truth.truth));
}

}  // namespace

void addDetectCommand(CLI::App& app) {
  auto o = std::make_shared<DetectOptions>();
  CLI::App* sub = app.add_subcommand(
      "detect", "Find the landmarks (poles) in every scan and label them across stops");
  sub->add_option("SEQ", o->seq, "Sequence directory (.pcd files, see docs/FORMAT.md)")->required();
  sub->add_option("-o,--out", o->out,
                  "Output directory: labelled scans, sequence.json, landmarks.csv")
      ->required();
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  CLI::Option* radius =
      sub->add_option("--radius", o->radius_m,
                      "Landmark radius in metres (default: sequence.json, else estimated)")
          ->check(CLI::PositiveNumber);
  sub->add_flag("--estimate-radius", o->estimate_radius,
                "Ignore sequence.json's radius and estimate it per landmark")
      ->excludes(radius);
  addThreadsOption(sub, o->threads, "detecting scans side by side");
  sub->add_option("--min-stops", o->min_stops,
                  "A landmark must be seen at this many stops (capped at the number of stops)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--link-distance", o->link_distance_m,
                  "Detections closer than this in the world frame (metres) belong to one landmark")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--max-missing-beams", o->max_missing_beams,
                  "Beams without return tolerated inside an object (raise to 2-3 for sensors that "
                  "drop many returns, "
                  "such as the YDLIDAR X4)")
      ->check(CLI::Range(0, 50))
      ->capture_default_str();
  addInlierThresholdOption(sub, o->inlier_threshold);
  sub->add_flag("--ascii", o->ascii, "Write ASCII PCD instead of binary");
  sub->add_option("--truth", o->truth,
                  "Simulator truth (DIR/truth.json, with DIR/true_ranges.csv): also print "
                  "precision, recall, purity "
                  "and errors by range");
  sub->callback([o] { runDetect(*o); });
}

}  // namespace lidarcal::pipeline
