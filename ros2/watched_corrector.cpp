// SPDX-License-Identifier: BSD-3-Clause
#include "ros2/watched_corrector.hpp"

#include <cstdio>
#include <utility>

#include "io/bag_scans.hpp"
#include "watch/diagnostics.hpp"

namespace lidarcal::ros2 {

namespace {

/// The distances the log lines and the diagnostics state a model's bias at, metres.
constexpr double kBiasDistancesM[] = {1.0, 2.0, 3.0};

LiveCorrector initialCorrector(const CalibrationModel* model, const LiveSettings& live) {
  if (!model) return LiveCorrector(live);
  return LiveCorrector(
      *model, live, pipeline::modelCorrector(*model, live.method, live.outside, live.model_file));
}

DiagnosticLevel levelOf(watch::Health h) {
  switch (h) {
    case watch::Health::ok:
      return DiagnosticLevel::ok;
    case watch::Health::warn:
      return DiagnosticLevel::warn;
    case watch::Health::error:
      return DiagnosticLevel::error;
  }
  return DiagnosticLevel::error;
}

/// The correction's counts, as the summary line states them.
void addCorrectionValues(const LiveStats& s, DiagnosticEntry& e) {
  const auto& c = s.correction;
  auto add = [&e](const char* key, std::size_t n) {
    e.values.emplace_back(key, std::to_string(n));
  };
  add("scans corrected", c.scans);
  add("scans passed uncorrected", s.uncorrected);
  add("returns corrected", c.corrected);
  add("returns outside the fitted readings", c.outside);
  add("returns without a distance", c.unresolved);
  add("malformed scans dropped", s.droppedTotal());
}

std::string entryName(const std::string& topic) { return "lidarcal: range model of " + topic; }

std::string stretchText(const watch::Stretch& s) {
  char text[96];
  std::snprintf(text, sizeof text, "scans %zu-%zu, %.1f m", s.first_scan, s.last_scan, s.length_m);
  return text;
}

}  // namespace

watch::WatchSettings watchSettingsFor(const NodeParameters& p) {
  watch::WatchSettings s = watch::defaultWatchSettings();
  s.mode = p.mode == NodeMode::learn ? watch::Mode::learn : watch::Mode::watch;
  if (p.false_alarms) s.false_alarms.per_unit = *p.false_alarms;
  s.false_alarms.unit = p.false_alarms_per_hour ? watch::Exposure::time : watch::Exposure::distance;
  if (p.check_every_m) s.check.every_m = *p.check_every_m;
  if (p.check_bias_replicas) s.check.bias_replicas = *p.check_bias_replicas;
  s.check.landmark_radius_m = p.landmark_radius_m;
  s.detection.landmark_radius_m = p.landmark_radius_m;
  return s;
}

WatchedCorrector::WatchedCorrector(const watch::WatchSettings& settings,
                                   std::shared_ptr<const CalibrationModel> model,
                                   const LiveSettings& live, std::size_t queue_scans)
    : settings_(settings),
      live_settings_(live),
      watcher_(settings, model, queue_scans),
      live_(initialCorrector(model.get(), live)) {
  seen_version_ = correcting_version_ = watcher_.modelVersion();
}

void WatchedCorrector::followSwitch() {
  switch_problem_.clear();
  const std::uint64_t version = watcher_.modelVersion();
  if (version == seen_version_) return;
  seen_version_ = version;
  const std::shared_ptr<const CalibrationModel> model = watcher_.model();
  if (!model) return;
  const std::string name = "the learnt model " + std::to_string(version);
  try {
    pipeline::checkModelInvertible(*model, name, live_settings_.outside);
    live_.useModel(*model, pipeline::modelCorrector(*model, live_settings_.method,
                                                    live_settings_.outside, name));
    correcting_version_ = version;
  } catch (const std::exception& e) {
    switch_problem_ =
        "the watcher switched to model " + std::to_string(version) +
        ", which cannot correct: " + e.what() + "; scans stay " +
        (live_.hasModel() ? "corrected with model " + std::to_string(correcting_version_)
                          : std::string("uncorrected"));
  }
}

ScanVerdict WatchedCorrector::process(ScanFields& scan, const RosTime& stamp,
                                      const PoseLookup& pose) {
  followSwitch();
  not_watched_.clear();
  io::RawScan raw;
  if (pose.pose) {  // the readings as received, before they are corrected in place
    io::LaserScanView view;
    view.stamp_sec = stamp.sec;
    view.stamp_nanosec = stamp.nanosec;
    view.angle_min = scan.angle_min;
    view.angle_increment = scan.angle_increment;
    view.range_min = scan.range_min;
    view.range_max = scan.range_max;
    view.ranges = scan.ranges;
    view.count = scan.beams;
    view.intensities = scan.intensity_values;
    view.intensity_count = scan.intensity_values ? scan.intensities : 0;
    io::fillRawScan(view, io::RosbagConfig{}, raw);
    raw.pose = *pose.pose;
  }
  const ScanVerdict verdict = live_.process(scan);
  if (verdict != ScanVerdict::publish) return verdict;
  if (!pose.pose) {
    ++without_pose_;
    not_watched_ = "no pose: " + pose.why;
  } else if (!watcher_.offer(std::move(raw))) {
    not_watched_ = "the watcher is behind (its queue of scans is full)";
  }
  return verdict;
}

DiagnosticEntry watchDiagnostics(const WatchedCorrector& w, const std::string& topic,
                                 const std::string& hardware_id) {
  const std::shared_ptr<const CalibrationModel> model = w.watcher().model();
  const watch::DiagnosticReport r = watch::diagnosticReport(
      w.watcher().state(), model.get(), w.settings(), w.watcher().dropped() + w.withoutPose());
  DiagnosticEntry e{levelOf(r.level), entryName(topic), r.message, hardware_id, r.values};
  e.values.emplace_back("scans without a pose", std::to_string(w.withoutPose()));
  addCorrectionValues(w.corrector().stats(), e);
  return e;
}

DiagnosticEntry applyDiagnostics(const LiveCorrector& c, const CalibrationModel& model,
                                 const std::string& model_file, const std::string& topic,
                                 const std::string& hardware_id) {
  DiagnosticEntry e{
      DiagnosticLevel::ok, entryName(topic), "correcting with " + model_file, hardware_id, {}};
  e.values.emplace_back("mode", "apply");
  e.values.emplace_back("model", model_file);
  watch::addBiasValues(model, e.values);
  addCorrectionValues(c.stats(), e);
  return e;
}

std::string switchLine(const watch::RefitEvent& e) {
  char head[160];
  std::snprintf(head, sizeof head, "switched to model %llu at scan %zu (%.1f m travelled): ",
                static_cast<unsigned long long>(e.model_version), e.decided_at, e.stretch.travel_m);
  std::string line = head;
  for (double d : kBiasDistancesM) {
    line += "bias at " + std::to_string(static_cast<int>(d)) + " m " +
            watch::biasText(*e.candidate, d) + " (was " +
            (e.previous ? watch::biasText(*e.previous, d) : std::string("no model")) + "), ";
  }
  return line + "learnt from " + stretchText(e.stretch) + "; " + e.decision.reason;
}

std::string candidateLine(const watch::RefitEvent& e, const std::string& published) {
  char head[96];
  std::snprintf(head, sizeof head, "refit at scan %zu on ", e.decided_at);
  return head + stretchText(e.stretch) + ": candidate " +
         (e.decision.adopt ? "adopted" : "not adopted") + " (" + e.decision.reason + "); " +
         published;
}

}  // namespace lidarcal::ros2
