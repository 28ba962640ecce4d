// SPDX-License-Identifier: BSD-3-Clause
// eval_detection: landmark detection and association measured against the simulator's truth,
// over several seeds of one or more scenes, in memory (no files written). Prints the Markdown
// tables of docs/results/detection.md.
//
//   build/bench/eval_detection --seeds 10 data/scenes/paper_field.json
//   data/scenes/field_clutter.json build/bench/eval_detection --estimate-radius --seeds 10
//   data/scenes/paper_field.json
//   build/bench/eval_detection --misses data/scenes/field_noisy.json   (lists what was missed and
//   why)

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <pcl/console/print.h>
#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "detectors/evaluation.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/scene_io.hpp"
#include "simulation/simulator.hpp"

namespace {

using namespace lidarcal;
using namespace lidarcal::detectors;

struct Options {
  std::vector<std::string> scenes;
  int seeds = 10;
  int first_seed = 1;
  bool estimate_radius = false;
  bool misses = false;
};

/// Sums over seeds of one scene.
struct Totals {
  std::size_t runs = 0, scans = 0, detections = 0, tp = 0, fp = 0, fp_clutter = 0, fp_walls = 0,
              observable = 0, detected = 0, with_id = 0, wrong_id = 0, split_ids = 0,
              runs_all_found = 0;
  std::size_t hidden = 0, hidden_detected = 0;
  std::size_t raw_detections = 0, raw_tp = 0, raw_detected = 0, raw_fp_clutter = 0,
              raw_fp_walls = 0;
  std::size_t clutter_beams = 0, object_beams = 0;
  struct Bin {
    double lo = 0, hi = 0;
    std::size_t observable = 0, detected = 0, n = 0, n_free = 0;
    double centre2 = 0, bearing2 = 0, range = 0, range2 = 0, free = 0, free2 = 0, radius = 0;
  };
  std::vector<Bin> bins;
  double radius_abs_error_sum = 0.0;
  std::size_t radius_estimates = 0;
};

void accumulate(Totals& t, const DetectionEvaluation& ev, const DetectionEvaluation& raw) {
  ++t.runs;
  t.scans += ev.scans;
  t.detections += ev.detections, t.tp += ev.true_positives, t.fp += ev.false_positives;
  t.fp_clutter += ev.false_on_clutter, t.fp_walls += ev.false_on_walls;
  t.observable += ev.observable, t.detected += ev.detected;
  t.hidden += ev.partly_hidden, t.hidden_detected += ev.partly_hidden_detected;
  t.with_id += ev.with_id, t.wrong_id += ev.wrong_id, t.split_ids += ev.split_ids;
  t.raw_detections += raw.detections, t.raw_tp += raw.true_positives,
      t.raw_detected += raw.detected;
  t.raw_fp_clutter += raw.false_on_clutter, t.raw_fp_walls += raw.false_on_walls;
  if (t.bins.empty())
    for (const auto& b : ev.bins) t.bins.push_back(Totals::Bin{b.lo_m, b.hi_m});
  for (std::size_t k = 0; k < ev.bins.size(); ++k) {
    const auto& b = ev.bins[k];
    auto& s = t.bins[k];
    const double n = double(b.detections), nf = double(b.free_radii);
    s.observable += b.observable, s.detected += b.detected, s.n += b.detections,
        s.n_free += b.free_radii;
    s.centre2 += n * b.centre_rms_m * b.centre_rms_m;
    s.bearing2 += n * b.bearing_rms_rad * b.bearing_rms_rad;
    s.range += n * b.range_bias_m, s.range2 += n * b.range_rms_m * b.range_rms_m;
    s.radius += n * b.radius_bias_m;
    s.free += nf * b.free_radius_bias_m, s.free2 += nf * b.free_radius_rms_m * b.free_radius_rms_m;
  }
}

void printMisses(const SequenceDetections& r, const std::vector<ScanTruth>& truth,
                 std::size_t landmarks, int min_beams) {
  for (std::size_t s = 0; s < r.scans.size(); ++s) {
    for (std::size_t l = 1; l <= landmarks; ++l) {
      std::vector<int> beams;
      for (std::size_t i = 0; i < truth[s].beams.size(); ++i)
        if (truth[s].returned[i] && truth[s].beams[i].target == io::TargetKind::landmark &&
            truth[s].beams[i].target_id == static_cast<int>(l))
          beams.push_back(static_cast<int>(i));
      if (static_cast<int>(beams.size()) < min_beams) continue;
      bool found = false;
      for (std::size_t j = 0; j < r.scans[s].detections.size(); ++j)
        for (auto i : r.scans[s].detections[j].inliers)
          if (i == beams[beams.size() / 2]) found = found || r.association.ids[s][j] != 0;
      if (found) continue;
      std::string why = "no cluster";
      for (const auto& c : r.scans[s].clusters) {
        const int b = beams[beams.size() / 2];
        const bool inside = c.first_index <= c.last_index
                                ? (b >= c.first_index && b <= c.last_index)
                                : (b >= c.first_index || b <= c.last_index);
        if (inside)
          why = std::string(toString(c.kind)) + " (" + std::to_string(c.points) +
                " points): " + (c.reason.empty() ? "circle not given an id" : c.reason);
      }
      std::printf("  miss: scan %zu landmark %zu (%zu beams): %s\n", s, l, beams.size(),
                  why.c_str());
    }
    for (std::size_t j = 0; j < r.scans[s].detections.size(); ++j) {
      const Detection& d = r.scans[s].detections[j];
      std::size_t on_landmark = 0;
      for (auto i : d.inliers)
        if (truth[s].beams[static_cast<std::size_t>(i)].target == io::TargetKind::landmark)
          ++on_landmark;
      if (2 * on_landmark > d.inliers.size()) continue;
      const auto& b = truth[s].beams[static_cast<std::size_t>(d.inliers[d.inliers.size() / 2])];
      std::printf(
          "  false: scan %zu id %d on %s %d: %zu/%zu points, range %.2f bearing %.1f deg, rms "
          "%.4f, free %s r=%.3f\n",
          s, r.association.ids[s][j], io::toString(b.target), b.target_id, d.inliers.size(),
          d.cluster_points, d.range_m, d.bearing_rad * 180 / 3.14159265, d.rms_m,
          toString(d.free_status), d.free_radius_m);
    }
  }
}

/// One seed of a scene simulated: the truth and every scan, with the stop each belongs to.
struct SimulatedRun {
  Truth truth;
  std::vector<simulation::SimulatedScan> sims;
  std::vector<std::size_t> stop_of_scan;
};

SimulatedRun simulateRun(const Scene& scene, std::uint64_t seed) {
  SimulatedRun run;
  run.truth.seed = seed;
  run.truth.scene = scene;
  run.truth.stops = simulation::planStops(scene, seed);
  simulation::SimulatedSequence sequence =
      simulation::simulateSequence(scene, run.truth.stops, seed);
  run.sims = std::move(sequence.scans);
  run.stop_of_scan = std::move(sequence.stop_of_scan);
  return run;
}

/// The detector is given the landmarks' radius when the scene publishes one common to all
/// (unless --estimate-radius).
SequenceDetectionConfig detectionConfig(const Scene& scene, const Options& o) {
  SequenceDetectionConfig cfg;
  bool common = !scene.landmarks.empty();
  for (const auto& l : scene.landmarks)
    common = common && l.radius_m == scene.landmarks.front().radius_m;
  if (scene.publish_landmark_radius && common && !o.estimate_radius)
    cfg.detection.landmark_radius_m = scene.landmarks.front().radius_m;
  return cfg;
}

/// Whether every landmark got exactly one id, and the errors of the radii the association
/// estimated.
void countIdentities(const Scene& scene, const SequenceDetections& r, const DetectionEvaluation& ev,
                     Totals& t) {
  std::vector<bool> found(scene.landmarks.size() + 1, false);
  for (int l : ev.truth_of_id)
    if (l > 0) found[static_cast<std::size_t>(l)] = true;
  bool all = true;
  for (std::size_t l = 1; l < found.size(); ++l) all = all && found[l];
  if (all && ev.ids == scene.landmarks.size()) ++t.runs_all_found;
  for (std::size_t id = 1; id <= ev.truth_of_id.size(); ++id) {
    const int l = ev.truth_of_id[id - 1];
    if (l > 0 && r.association.landmarks[id - 1].radius_estimated) {
      t.radius_abs_error_sum += std::abs(r.association.landmarks[id - 1].radius_m -
                                         scene.landmarks[std::size_t(l - 1)].radius_m);
      ++t.radius_estimates;
    }
  }
}

/// Detects and evaluates one seed of the scene, adding to the scene's totals.
void runSeed(const Scene& scene, std::uint64_t seed, const Options& o, Totals& t) {
  const SimulatedRun run = simulateRun(scene, seed);
  const auto& sims = run.sims;
  const SequenceDetections r = detectSequence(
      sims.size(), [&](std::size_t i) { return sims[i].scan; }, run.stop_of_scan,
      detectionConfig(scene, o));
  std::vector<ScanTruth> st;
  for (std::size_t i = 0; i < sims.size(); ++i) {
    for (const auto& b : sims[i].truth)
      if (b.target != io::TargetKind::none && b.target != io::TargetKind::wall) {
        ++t.object_beams;
        if (b.target == io::TargetKind::clutter) ++t.clutter_beams;
      }
    st.push_back(makeScanTruth(run.truth, i, sims[i].truth, *sims[i].scan.cloud));
  }
  const EvaluationConfig ecfg;
  const DetectionEvaluation ev = evaluateDetections(r.scans, &r.association, st, run.truth, ecfg);
  const DetectionEvaluation raw = evaluateDetections(r.scans, nullptr, st, run.truth, ecfg);
  accumulate(t, ev, raw);
  countIdentities(scene, r, ev, t);
  if (o.misses) {
    std::printf("seed %llu: %zu ids, precision %.4f recall %.4f purity %.4f\n",
                static_cast<unsigned long long>(seed), ev.ids, ev.precision, ev.recall, ev.purity);
    printMisses(r, st, scene.landmarks.size(), ecfg.min_beams);
  }
}

double ratio(std::size_t a, std::size_t b) { return b ? double(a) / double(b) : 1.0; }

/// The scene's section of docs/results/detection.md: the detection table and the table by range.
void printTotals(const std::string& file, const Scene& scene, const Options& o, const Totals& t) {
  std::printf("\n### %s\n\n", file.c_str());
  std::printf(
      "%s; %zu landmarks, %zu clutter cylinders, %zu wall segments; %d seeds x %zu scans; radius "
      "%s; "
      "clutter returns: %.1f%% of the returns on round objects\n\n",
      scene.name.c_str(), scene.landmarks.size(), scene.clutter.size(), scene.walls.size(), o.seeds,
      t.scans / std::max<std::size_t>(t.runs, 1),
      (scene.publish_landmark_radius && !o.estimate_radius) ? "known (sequence.json)" : "estimated",
      100.0 * ratio(t.clutter_beams, t.object_beams));
  std::printf(
      "| stage | detections | precision | recall (observable: %zu) | false on clutter | false on "
      "walls | purity | wrong ids | split ids | runs with every landmark one id |\n",
      t.observable);
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  std::printf("| per scan (before association) | %zu | %.4f | %.4f | %zu | %zu | | | | |\n",
              t.raw_detections, ratio(t.raw_tp, t.raw_detections),
              ratio(t.raw_detected, t.observable), t.raw_fp_clutter, t.raw_fp_walls);
  std::printf(
      "| labelled (after association) | %zu | %.4f | %.4f | %zu | %zu | %.4f | %zu | %zu | %zu / "
      "%zu |\n",
      t.detections, ratio(t.tp, t.detections), ratio(t.detected, t.observable), t.fp_clutter,
      t.fp_walls, 1.0 - ratio(t.wrong_id, t.with_id), t.wrong_id, t.split_ids, t.runs_all_found,
      t.runs);
  std::printf("\nPartly hidden observations (excluded from recall): %zu, of which detected %zu.\n",
              t.hidden, t.hidden_detected);
  if (t.radius_estimates)
    std::printf("\nJoint radius estimates: mean |error| %.4f m over %zu landmark estimates.\n",
                t.radius_abs_error_sum / double(t.radius_estimates), t.radius_estimates);
  std::printf(
      "\n| true range D (m) | observable | recall | centre RMS vs truth (m) | bearing RMS (mrad) | "
      "range - (f(D-R)+R): mean (m) | RMS (m) | free radius error: mean (m) | RMS (m) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& b : t.bins) {
    if (!b.observable && !b.n) continue;
    const double n = std::max<double>(double(b.n), 1.0),
                 nf = std::max<double>(double(b.n_free), 1.0);
    std::printf("| %.0f-%.0f | %zu | %.4f | %.4f | %.2f | %+.4f | %.4f | %+.4f | %.4f |\n", b.lo,
                b.hi, b.observable, ratio(b.detected, b.observable), std::sqrt(b.centre2 / n),
                1e3 * std::sqrt(b.bearing2 / n), b.range / n, std::sqrt(b.range2 / n), b.free / nf,
                std::sqrt(b.free2 / nf));
  }
}

void runScene(const std::string& file, const Options& o) {
  const Scene scene = io::readScene(file);
  Totals t;
  for (int k = 0; k < o.seeds; ++k)
    runSeed(scene, static_cast<std::uint64_t>(o.first_seed + k), o, t);
  printTotals(file, scene, o, t);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Detection and association against the simulator's truth (docs/RESULTS.md, section "
      "Detection)"};
  Options o;
  app.add_option("SCENES", o.scenes, "Scene files (data/scenes/*.json)")->required();
  app.add_option("--seeds", o.seeds, "Seeds per scene")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--first-seed", o.first_seed, "First seed")->capture_default_str();
  app.add_flag("--estimate-radius", o.estimate_radius,
               "Do not give the detector the landmark radius");
  app.add_flag("--misses", o.misses, "List every missed observation with the reason");
  CLI11_PARSE(app, argc, argv);
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // our statuses say what PCL would print
  try {
    for (const auto& s : o.scenes) runScene(s, o);
  } catch (const lidarcal::InputError& e) {
    std::fprintf(stderr, "eval_detection: %s\n", e.what());
    return 2;
  }
  return 0;
}
