// SPDX-License-Identifier: BSD-3-Clause
// lidarcal watch INPUT --model M.json -o DIR [--pose odom:TOPIC|tf:FRAME] [--mode watch|learn]
// Replays a recording (a sequence directory, or a bag, log or CSV that `import` reads) through the
// field watcher (watch/engine.hpp) as the live nodes run it, and writes the timeline: every check,
// every alarm with its scan and evidence, every switch (DIR/timeline.json, timeline.png; the
// models learnt under DIR/models/). It exits 0 whether or not it raised an alarm; 3 when no check
// could be made at all (the recording does not let the poles check the model).

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <glog/logging.h>
#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/gnuplot.hpp"
#include "io/model_io.hpp"
#include "io/output_files.hpp"
#include "io/raw_scan_cloud.hpp"
#include "io/sequence.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/watch_report.hpp"
#include "pipeline/stages/import.hpp"
#include "watch/engine.hpp"

namespace lidarcal::pipeline {
namespace fs = std::filesystem;
namespace {

struct WatchOptions {
  std::string input, model, out, from, topic, pose, mode = "watch", per = "km", inject;
  double false_alarms = watch::FalseAlarmRate{}.per_unit;
  double every_m = watch::CheckSettings{}.every_m;
  double radius_m = 0.0;
  int bias_replicas = watch::CheckSettings{}.bias_replicas;
  bool overwrite = false;
};

watch::WatchSettings settingsFrom(const WatchOptions& o, std::optional<double> radius) {
  watch::WatchSettings s = watch::defaultWatchSettings();
  if (!watch::parseMode(o.mode, s.mode))
    throw InputError("", "--mode", "'" + o.mode + "' is not watch or learn", "use --mode watch");
  if (!(o.false_alarms > 0.0))
    throw InputError("", "--false-alarms", "must be > 0", "e.g. --false-alarms 0.1");
  s.false_alarms.per_unit = o.false_alarms;
  s.false_alarms.unit = o.per == "hour" ? watch::Exposure::time : watch::Exposure::distance;
  if (!(o.every_m > 0.0))
    throw InputError("", "--check-every", "must be > 0 metres", "e.g. --check-every 3");
  s.check.every_m = o.every_m;
  if (o.bias_replicas < 0 || o.bias_replicas > 100)
    throw InputError("", "--check-bias-replicas", "must be in 0..100",
                     "e.g. --check-bias-replicas 4");
  s.check.bias_replicas = o.bias_replicas;
  s.check.landmark_radius_m = radius;
  s.detection.landmark_radius_m = radius;
  return s;
}

std::shared_ptr<const CalibrationModel> loadModel(const WatchOptions& o, watch::Mode mode) {
  if (o.model.empty()) {
    if (mode == watch::Mode::learn) return nullptr;
    throw InputError("", "--model", "watch mode checks a model and none was given",
                     "give --model model.json (of `lidarcal calibrate`), or --mode learn");
  }
  auto m = std::make_shared<const CalibrationModel>(io::readModel(o.model));
  if (!m->status.ok())
    throw DataError(o.model, "diagnostics.status",
                    "the model has no usable fit (" + m->status.message + ")",
                    "calibrate again, or watch with --mode learn and no --model");
  const std::size_t n = m->model.bias.alpha.size();
  if (m->alpha_covariance.size() != n * n)
    throw InputError(o.model, "alpha_covariance",
                     "is missing, so no check can tell the model's own error from a change of "
                     "the sensor",
                     "use a model.json written by `lidarcal calibrate`, which records it");
  return m;
}

/// Feeds every scan of the input to `on_scan`; returns the scans read.
std::size_t replay(const WatchOptions& o, const std::function<void(io::RawScan&)>& on_scan,
                   std::optional<double>& radius, std::size_t& total) {
  std::error_code ec;
  if (fs::is_directory(o.input, ec) && fs::exists(fs::path(o.input) / "sequence.json", ec)) {
    const io::Sequence seq = io::openSequence(o.input);
    if (!radius) radius = seq.meta.landmark_radius_m;
    total = seq.scans.size();
    const double lo = seq.meta.range_min_m.value_or(0.0), hi = seq.meta.range_max_m.value_or(1e9);
    for (std::size_t i = 0; i < seq.scans.size(); ++i) {
      io::RawScan raw = io::toRawScan(io::readScan(seq.scans[i].path), lo, hi);
      on_scan(raw);
    }
    return seq.scans.size();
  }
  ImportSettings s;
  s.format = o.from.empty() ? detectImportFormat(o.input) : parseImportFormat(o.from);
  s.topic = o.topic;
  if (!o.pose.empty()) {
    if (!isBag(s.format))
      throw InputError("", "--pose",
                       "applies to ROS bags only (other recordings carry their poses)",
                       "drop --pose");
    s.bag_pose = parseBagPose(o.pose);
  }
  std::size_t n = 0;
  readRecording(s, o.input, [&](const io::RawScan& scan) {
    io::RawScan copy = scan;
    on_scan(copy);
    ++n;
    return true;
  });
  return n;
}

/// Writes DIR; returns what it holds, for the user.
std::string writeOutputs(const WatchOptions& o, const WatchTimeline& t) {
  io::checkOutsideInput(o.input, o.out);
  io::StagedDirectory dir(o.out, o.overwrite);
  std::string json = timelineJson(t).dump(2);
  io::writeTextAtomically(dir.path() / "timeline.json", json + "\n");
  std::string written = "timeline.json";
  bool models = false;
  for (const auto& r : t.refits)
    if (!r.model_file.empty()) {
      if (!models) io::makeDirectory(dir.path() / "models");
      models = true;
      io::writeModel(dir.path() / r.model_file, *r.event.candidate);
    }
  if (models) written += ", models/";
  std::string why = "no test was made, so there is nothing to draw";
  if (writeTimelinePlot(dir.path(), t) > 0 && io::runGnuplot(dir.path(), "timeline.gp", &why))
    written += ", timeline.png";
  else if (!quiet())
    std::fprintf(stderr, "lidarcal watch: no plot (%s)\n", why.c_str());
  dir.commit();
  return written;
}

/// The change --inject asks for, if any.
std::optional<watch::RangeChange> injection(const WatchOptions& o) {
  if (o.inject.empty()) return std::nullopt;
  try {
    return watch::parseRangeChange(o.inject);
  } catch (const std::invalid_argument& e) {
    throw InputError("", "--inject", e.what(), "e.g. --inject 20@300 (20 mm from scan 300)");
  }
}

/// A sink that records every check and refit in `t` and prints the lines worth a user's eye.
watch::WatchSink recordingSink(WatchTimeline& t) {
  watch::WatchSink sink;
  sink.check = [&t](const watch::CheckEvent& e) {
    t.checks.push_back(e);
    if (const std::string line = checkLine(e); !line.empty()) std::printf("%s\n", line.c_str());
  };
  sink.refit = [&t](const watch::RefitEvent& e) {
    RefitRecord r{e, ""};
    if (e.decision.adopt)
      r.model_file = "models/model_v" + std::to_string(e.model_version) + ".json";
    else
      r.event.candidate.reset();  // a summary is enough; memory stays small on long logs
    r.event.previous.reset();
    t.refits.push_back(std::move(r));
    if (const std::string line = refitLine(e); !line.empty()) std::printf("%s\n", line.c_str());
  };
  return sink;
}

/// Exit 3 when the recording allowed neither a model (learn without one) nor a test: the
/// timeline is written, and the message says what to record instead.
void refuseWithoutResult(const WatchOptions& o, const WatchTimeline& t) {
  if (t.final_state.model_version == 0)
    throw DataError(o.input, "",
                    "no model could be learnt on this recording (" +
                        std::to_string(t.refits.size()) + " refits over " +
                        std::to_string(static_cast<int>(t.final_state.travel_m)) + " m): " +
                        (t.refits.empty() ? std::string("too little travel for a refit")
                                          : t.refits.back().event.decision.reason),
                    "record a longer drive past poles (a bag with its poses: --pose)");
  if (t.final_state.checks == 0)
    throw DataError(o.input, "",
                    "no test of the model could be made on this recording (" +
                        std::to_string(t.checks.size()) + " checks tried over " +
                        std::to_string(t.final_state.scans) + " scans, " +
                        std::to_string(static_cast<int>(t.final_state.travel_m)) +
                        " m): a test needs " + std::to_string(t.settings.check.baseline_checks) +
                        " checks, each on poles seen from a robot driving " +
                        std::to_string(static_cast<int>(t.settings.check.every_m)) + " m",
                    "record a longer drive past poles (a bag with its poses: --pose), and read "
                    "timeline.json for why each check could not be made");
}

void runWatch(const WatchOptions& o) {
  // A refit on a stretch that cannot determine a model makes Ceres warn (through glog) of a
  // rank-deficient covariance; the refit's decision says so in the timeline instead.
  FLAGS_minloglevel = google::GLOG_ERROR;
  if (o.out.empty())
    throw InputError("", "--out", "no output directory given", "give -o DIR for the timeline");
  if (o.per != "km" && o.per != "hour")
    throw InputError("", "--per", "'" + o.per + "' is not km or hour", "use --per km");
  const std::optional<watch::RangeChange> change = injection(o);
  std::optional<double> radius;
  if (o.radius_m > 0.0) radius = o.radius_m;
  watch::WatchSettings settings = settingsFrom(o, radius);
  const auto model = loadModel(o, settings.mode);
  if (!o.overwrite && fs::exists(o.out))
    throw InputError(o.out, "--out", "exists", "choose another directory or give --overwrite");

  WatchTimeline t;
  t.input = o.input;
  t.model_file = o.model;
  t.injected = change;
  const watch::WatchSink sink = recordingSink(t);
  std::unique_ptr<watch::Engine> engine;
  std::size_t index = 0, total = 0;
  Progress progress("watching", 0, !quiet());
  replay(
      o,
      [&](io::RawScan& scan) {
        if (!engine) {
          settings = settingsFrom(o, radius);  // a sequence's radius is known once it is open
          engine =
              std::make_unique<watch::Engine>(settings, model, watch::FitExecution::at_scan, sink);
        }
        if (change) watch::applyChange(*change, index, scan);
        engine->observe(scan);
        progress.update(++index, total);
      },
      radius, total);
  progress.finish();
  if (!engine) throw DataError(o.input, "", "holds no scan to watch", "check --topic and --from");
  engine->finish();
  t.settings = settings;
  t.final_state = engine->state();
  const std::string written = writeOutputs(o, t);
  std::printf("%s", watchSummary(t).c_str());
  std::printf("Output: %s (%s)\n", o.out.c_str(), written.c_str());
  refuseWithoutResult(o, t);
}

}  // namespace

void addWatchCommand(CLI::App& app) {
  auto o = std::make_shared<WatchOptions>();
  CLI::App* sub = app.add_subcommand(
      "watch",
      "Replay a recording through the field watcher: check the range model against the poles "
      "passed at a set false-alarm rate, and in learn mode learn a new one (the nodes' watch "
      "and learn modes)");
  sub->add_option("INPUT", o->input,
                  "A sequence directory, or a recording `import` reads (bag, .mcap, .db3, log, "
                  "CSV) with poses")
      ->required();
  sub->add_option("--model", o->model, "The model in use (model.json); optional with --mode learn");
  sub->add_option("-o,--out", o->out, "Output directory: timeline.json, timeline.png, models/")
      ->required();
  sub->add_option("--mode", o->mode, "watch (check the model; default) or learn (also switch)")
      ->check(CLI::IsMember({"watch", "learn"}));
  sub->add_option("--false-alarms", o->false_alarms,
                  "Expected false alarms per km (or per hour with --per hour) while the sensor "
                  "matches the model")
      ->capture_default_str();
  sub->add_option("--per", o->per, "km (default) or hour (of driving: needs time stamps)");
  sub->add_option("--check-every", o->every_m, "Metres of travel between checks")
      ->capture_default_str();
  sub->add_option("--check-bias-replicas", o->bias_replicas,
                  "Replicas that estimate a check fit's own bias by a parametric bootstrap, "
                  "for the checks tested against zero: the baseline's, and in learn mode those "
                  "after it failed (0: none; each costs one more fit)")
      ->capture_default_str();
  sub->add_option("--radius", o->radius_m,
                  "Pole radius in metres (default: sequence.json, else estimated)");
  sub->add_option("--inject", o->inject,
                  "Inject a change into the readings from a scan on: OFFSET_MM@SCAN, SCALE%@SCAN "
                  "or both, e.g. 20@300 (to see what the watcher catches on this log)");
  sub->add_option("--from", o->from, "Recording format, as `import --from` (default: detected)");
  sub->add_option("--topic", o->topic, "LaserScan topic of a bag (default: the only one)");
  sub->add_option("--pose", o->pose, "Poses of a bag: odom:TOPIC or tf:FIXED_FRAME");
  sub->add_flag("--overwrite", o->overwrite, "Replace DIR if it exists");
  sub->callback([o] { runWatch(*o); });
}

}  // namespace lidarcal::pipeline
