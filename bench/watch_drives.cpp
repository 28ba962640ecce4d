// SPDX-License-Identifier: BSD-3-Clause
// watch_drives: the field watcher on simulated drives with a known truth (docs/results/watch.md).
// Each seed drives a scene's route (data/scenes/, path.kind driving) for --scans scans, optionally
// with a change of the sensor injected from a scan on, and replays it through watch::Engine with
// the model given by --model: `truth` (the scene's own sensor, standard errors zero) or a file
// (model.json of `lidarcal calibrate` on another drive). Prints one line per seed and a summary:
// alarms before the change (false) and the first after it (detected: scans, metres and poles
// passed since the change), checks and their levels; with --learn the switch and the corrected
// error against the truth before and after it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "calibration/filtering.hpp"
#include "child_process.hpp"
#include "common/errors.hpp"
#include "io/model_io.hpp"
#include "io/raw_scan_cloud.hpp"
#include "io/scene_io.hpp"
#include "io/sequence_writer.hpp"
#include "simulation/simulator.hpp"
#include "simulation/truth_model.hpp"
#include "watch/engine.hpp"
#include "watch/range_change.hpp"

using namespace lidarcal;

namespace {

struct Options {
  std::string scene, model = "truth", change, csv;
  std::size_t first_seed = 1, seeds = 20, scans = 2000;
  double rate = 0.1, every_m = 3.0;
  int bias_replicas = watch::CheckSettings{}.bias_replicas;
  bool per_hour = false, learn = false, radius = true, verbose = false;
  double scan_hz = 10.0;
  std::size_t rss_every = 0;
  std::string work;  // --learn: where the post-change scans are written for a fresh calibrate
};

/// Resident memory of this process, MiB (Linux /proc/self/statm).
double residentMiB() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return NAN;
  long pages = 0, resident = 0;
  const int n = std::fscanf(f, "%ld %ld", &pages, &resident);
  std::fclose(f);
  return n == 2 ? static_cast<double>(resident) * 4096.0 / (1024.0 * 1024.0) : NAN;
}

struct SeedResult {
  std::size_t checks = 0, failed = 0, false_alarms = 0, tests_before = 0, exceed_before = 0;
  double levels_before = 0.0;
  // the same for the absolute tests alone (the rest are change tests)
  std::size_t absolute_before = 0, absolute_exceed = 0;
  double absolute_levels = 0.0;
  long detected_at = -1;
  double detect_m = NAN, change_m = NAN;
  std::size_t poles_passed = 0;
  long switched_at = -1;
  double err_switched = NAN, err_fresh = NAN,
         err_raw = NAN;  // RMS on the poles after the switch, m
  std::shared_ptr<const CalibrationModel> switched;
  double seconds = 0.0;
  std::vector<double> p_values;
  std::vector<double> refit_p;  // the difference test's p of each refit judged against a model
};

/// RMS of corrected minus true range over the pole beams of the scans from `first` on (raw
/// readings when `model` is null), metres.
double poleError(const CalibrationModel* model, const std::vector<io::RawScan>& scans,
                 const std::vector<std::vector<io::TrueRange>>& truth, std::size_t first) {
  std::optional<calibration::ReadingCorrector> correct;
  if (model)
    correct = calibration::readingCorrector(*model, calibration::InversionMethod::ls,
                                            calibration::kDefaultOutside);
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t k = first; k < scans.size(); ++k)
    for (const auto& t : truth[k]) {
      const double y = scans[k].ranges_m[t.beam];
      if (t.target != io::TargetKind::landmark || !std::isfinite(y) || !std::isfinite(t.range_m))
        continue;
      const double d = correct ? (*correct)(y).range_m : y;
      if (!std::isfinite(d)) continue;
      sum += (d - t.range_m) * (d - t.range_m);
      ++n;
    }
  return n ? std::sqrt(sum / static_cast<double>(n)) : NAN;
}

/// The model switched to against `lidarcal calibrate` on all the scans after the change: both
/// models' corrected error on the pole beams of the scans after the switch.
void compareWithFresh(const Options& o, std::uint64_t seed, const watch::RangeChange& change,
                      const std::vector<io::RawScan>& after,
                      const std::vector<std::vector<io::TrueRange>>& truth, SeedResult& r) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(o.work) / ("seed" + std::to_string(seed));
  fs::create_directories(dir);
  io::SequenceWriterConfig wc;
  wc.overwrite = true;
  io::SequenceWriter writer(dir / "after", wc);
  for (const auto& scan : after) writer.add(scan);
  writer.commit("simulated");
  const fs::path model = dir / "fresh.json";
  const auto m = bench::runChild(LIDARCAL_EXE, {"calibrate", "-q", (dir / "after").string(), "-o",
                                                model.string(), "--overwrite"});
  if (m.exit_code != 0) return;
  const CalibrationModel fresh_model = io::readModel(model);
  const std::size_t first = static_cast<std::size_t>(r.switched_at) + 1 - change.from_scan;
  r.err_switched = poleError(r.switched.get(), after, truth, first);
  r.err_fresh = poleError(&fresh_model, after, truth, first);
  r.err_raw = poleError(nullptr, after, truth, first);
}

/// A sink that counts the checks, false alarms, the detection and the switch of one drive in `r`.
watch::WatchSink seedSink(const Options& o, const watch::RangeChange& change, SeedResult& r) {
  watch::WatchSink sink;
  sink.check = [&o, &change, &r](const watch::CheckEvent& e) {
    if (!e.check.status.ok()) {
      ++r.failed;
      if (o.verbose)
        std::fprintf(stderr, "check %zu-%zu: not possible: %s\n", e.stretch.first_scan,
                     e.stretch.last_scan, e.check.status.message.c_str());
      return;
    }
    if (o.verbose)
      std::fprintf(stderr,
                   "check %zu-%zu: %s record %zu poles %zu readings %zu shift %.2f +- %.2f mm at "
                   "%.2f, %.2f +- %.2f mm at %.2f (fit's own bias: %.2f, %.2f mm), "
                   "p %.3g\n",
                   e.stretch.first_scan, e.stretch.last_scan, watch::toString(e.test), e.record,
                   e.check.poles, e.check.readings, 1e3 * e.check.shift_m[0],
                   1e3 * e.check.shift_se_m[0], e.check.distance_m[0], 1e3 * e.check.shift_m[1],
                   1e3 * e.check.shift_se_m[1], e.check.distance_m[1], 1e3 * e.check.fit_bias_m[0],
                   1e3 * e.check.fit_bias_m[1], e.f.p);
    if (e.test == watch::Test::baseline) return;
    ++r.checks;
    r.p_values.push_back(e.f.p);
    const bool after = !change.none() && e.stretch.last_scan >= change.from_scan;
    if (e.alarm && !after) ++r.false_alarms;
    if (!after) {
      ++r.tests_before;
      r.levels_before += e.level;
      r.exceed_before += e.exceeds;
      if (e.test == watch::Test::absolute) {
        ++r.absolute_before;
        r.absolute_levels += e.level;
        r.absolute_exceed += e.exceeds;
      }
    }
    if (e.alarm && after && r.detected_at < 0) {
      r.detected_at = static_cast<long>(e.decided_at);
      r.detect_m = e.stretch.travel_m;
    }
  };
  sink.refit = [&r](const watch::RefitEvent& e) {
    if (e.decision.test.tested) r.refit_p.push_back(e.decision.test.f.p);
    if (e.decision.adopt && r.switched_at < 0) {
      r.switched_at = static_cast<long>(e.decided_at);
      r.switched = e.candidate;
    }
  };
  return sink;
}

SeedResult runSeed(const Scene& scene, const std::shared_ptr<const CalibrationModel>& model,
                   const Options& o, std::uint64_t seed, const watch::RangeChange& change) {
  SeedResult r;
  watch::WatchSettings ws = watch::defaultWatchSettings();
  ws.mode = o.learn ? watch::Mode::learn : watch::Mode::watch;
  ws.false_alarms.per_unit = o.rate;
  ws.false_alarms.unit = o.per_hour ? watch::Exposure::time : watch::Exposure::distance;
  ws.check.every_m = o.every_m;
  ws.check.bias_replicas = o.bias_replicas;
  if (o.radius && !scene.landmarks.empty())
    ws.check.landmark_radius_m = scene.landmarks[0].radius_m;
  ws.detection.landmark_radius_m = ws.check.landmark_radius_m;
  const watch::WatchSink sink = seedSink(o, change, r);
  watch::Engine engine(ws, model, watch::FitExecution::at_scan, sink);
  const auto stops = simulation::planStops(scene, seed);
  std::set<int> poles_after;
  std::vector<io::RawScan> after;                 // learn: the scans after the change
  std::vector<std::vector<io::TrueRange>> truth;  // and their truth
  const bool fresh = o.learn && !change.none() && !o.work.empty();
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < stops.size() && i < o.scans; ++i) {
    const auto sim = simulation::simulateScan(scene, stops[i], i, seed);
    io::RawScan raw =
        io::toRawScan(sim.scan, scene.sensor.range.range_min_m, scene.sensor.range.range_max_m);
    raw.stamp_s = static_cast<double>(i) / o.scan_hz;
    watch::applyChange(change, i, raw);
    if (!change.none() && i == change.from_scan) r.change_m = engine.state().travel_m;
    engine.observe(raw);
    if (fresh && i >= change.from_scan) {
      after.push_back(raw);
      truth.push_back(sim.truth);
    }
    if (o.rss_every && (i + 1) % o.rss_every == 0)
      std::printf(
          "  scan %zu: %.1f MiB resident, %zu sightings in the window, %zu tracks, %zu "
          "tests\n",
          i + 1, residentMiB(), engine.state().sightings, engine.state().tracks,
          engine.state().checks);
    if (!change.none() && i >= change.from_scan && r.detected_at < 0)
      for (const auto& t : sim.truth)
        if (t.target == io::TargetKind::landmark) poles_after.insert(t.target_id);
  }
  engine.finish();
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.poles_passed = poles_after.size();
  if (fresh && r.switched) compareWithFresh(o, seed, change, after, truth, r);
  return r;
}

/// Sums over the seeds.
struct Summary {
  std::size_t detected = 0, false_alarms = 0, checks = 0, with_false = 0, exceeding = 0;
  double levels = 0.0;  ///< sum of the levels of the tests before the change
  std::size_t abs_tests = 0, abs_exceeding = 0;
  double abs_levels = 0.0;
  std::size_t refits = 0, refits_05 = 0, refits_01 = 0, switched = 0;
};

void addSeed(Summary& s, const SeedResult& r) {
  s.checks += r.checks;
  s.exceeding += r.exceed_before;
  s.abs_tests += r.absolute_before;
  s.abs_exceeding += r.absolute_exceed;
  s.abs_levels += r.absolute_levels;
  s.levels += r.levels_before;
  s.false_alarms += r.false_alarms;
  s.with_false += r.false_alarms > 0;
  s.detected += r.detected_at >= 0;
  s.switched += r.switched_at >= 0;
  s.refits += r.refit_p.size();
  for (double p : r.refit_p) s.refits_05 += p < 0.05, s.refits_01 += p < 0.01;
}

/// The seed's line: checks, alarms, detection, switch, and the tests' p-values.
void printSeed(std::uint64_t seed, const SeedResult& r, const watch::RangeChange& change,
               const Options& o) {
  std::printf("seed %3llu: %3zu checks (%zu not possible), %zu false alarms",
              static_cast<unsigned long long>(seed), r.checks, r.failed, r.false_alarms);
  if (!change.none()) std::printf(", detected %s", r.detected_at < 0 ? "no" : "");
  if (r.detected_at >= 0)
    std::printf("at scan %ld (%ld scans, %.1f m, %zu poles after the change)", r.detected_at,
                r.detected_at - static_cast<long>(change.from_scan), r.detect_m - r.change_m,
                r.poles_passed);
  if (o.learn) std::printf(", switched at %ld", r.switched_at);
  if (std::isfinite(r.err_switched))
    std::printf(
        " (pole error after it: %.2f mm with the model switched to, %.2f mm with "
        "`calibrate` on the scans after the change, %.2f mm raw)",
        1000.0 * r.err_switched, 1000.0 * r.err_fresh, 1000.0 * r.err_raw);
  std::printf("; p:");
  for (double p : r.p_values) std::printf(" %.2g", p);
  if (!r.refit_p.empty()) std::printf("; refits' p:");
  for (double p : r.refit_p) std::printf(" %.2g", p);
  std::printf("  [%.1f s]\n", r.seconds);
  std::fflush(stdout);
}

void printSummary(const Summary& s, const Options& o) {
  std::printf(
      "seeds %zu, tests %zu, false alarms %zu (drives with one: %zu), detected %zu; "
      "before the change %zu tests exceeded their level, %.2f expected (sum of levels)\n",
      o.seeds, s.checks, s.false_alarms, s.with_false, s.detected, s.exceeding, s.levels);
  std::printf(
      "of which change tests %zu exceeded, %.2f expected; absolute tests (%zu) %zu exceeded, "
      "%.2f expected\n",
      s.exceeding - s.abs_exceeding, s.levels - s.abs_levels, s.abs_tests, s.abs_exceeding,
      s.abs_levels);
  if (o.learn)
    std::printf(
        "learn: %zu drives switched; %zu refits compared with the model in use, p < 0.05 in "
        "%zu, p < 0.01 in %zu\n",
        s.switched, s.refits, s.refits_05, s.refits_01);
}

void addOptions(CLI::App& app, Options& o) {
  app.add_option("--scene", o.scene, "Scene (path.kind driving)")->required();
  app.add_option("--model", o.model, "truth, or a model.json");
  app.add_option("--change", o.change, "Change injected: OFFSET_MM@SCAN, SCALE%@SCAN");
  app.add_option("--first-seed", o.first_seed, "First seed");
  app.add_option("--seeds", o.seeds, "Seeds");
  app.add_option("--scans", o.scans, "Scans per drive");
  app.add_option("--rate", o.rate, "False alarms per km (per hour with --per-hour)");
  app.add_flag("--per-hour", o.per_hour, "The rate per hour of driving (scans at --scan-hz)");
  app.add_option("--scan-hz", o.scan_hz, "Scans per second");
  app.add_option("--every", o.every_m, "Metres between checks");
  app.add_option("--bias-replicas", o.bias_replicas,
                 "Bootstrap replicas for the check fit's own bias, on the checks tested against "
                 "zero (0: none)")
      ->capture_default_str();
  app.add_flag("--learn", o.learn, "Learn mode");
  app.add_flag("!--no-radius", o.radius, "Do not give the watcher the poles' radius");
  app.add_flag("--verbose", o.verbose,
               "Each check on stderr (baseline checks too, with the fit's own bias)");
  app.add_option("--rss-every", o.rss_every, "Print resident memory every N scans");
  app.add_option("--work", o.work,
                 "With --learn and --change: a directory for the scans after the change, which "
                 "`lidarcal calibrate` fits afresh to compare its corrected error with the model "
                 "switched to");
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"The field watcher on simulated drives (docs/results/watch.md)"};
  addOptions(app, o);
  CLI11_PARSE(app, argc, argv);
  try {
    Scene scene = io::readScene(o.scene);
    scene.path.stops = static_cast<int>(o.scans);
    const auto model = std::make_shared<const CalibrationModel>(
        o.model == "truth" ? simulation::truthModel(scene) : io::readModel(o.model));
    const watch::RangeChange change =
        o.change.empty() ? watch::RangeChange{} : watch::parseRangeChange(o.change);
    Summary summary;
    for (std::size_t k = 0; k < o.seeds; ++k) {
      const std::uint64_t seed = o.first_seed + k;
      const SeedResult r = runSeed(scene, model, o, seed, change);
      addSeed(summary, r);
      printSeed(seed, r, change, o);
    }
    printSummary(summary, o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "watch_drives: %s\n", e.what());
    return 2;
  }
}
