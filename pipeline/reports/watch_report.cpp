// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/watch_report.hpp"

#include <cstdio>
#include <sstream>

#include "io/atomic_file.hpp"
#include "io/json_number.hpp"

namespace lidarcal::pipeline {

namespace {

using nlohmann::ordered_json;

ordered_json pair(const std::array<double, 2>& v) {
  return {io::jsonNumber(v[0]), io::jsonNumber(v[1])};
}

ordered_json stretchJson(const watch::Stretch& s) {
  return {{"first_scan", s.first_scan},
          {"last_scan", s.last_scan},
          {"travel_m", io::jsonNumber(s.travel_m)},
          {"length_m", io::jsonNumber(s.length_m)},
          {"stamp_s", io::jsonNumber(s.stamp_s)}};
}

ordered_json checkJson(const watch::CheckEvent& e) {
  ordered_json j = stretchJson(e.stretch);
  j["decided_at_scan"] = e.decided_at;
  j["status"] = toString(e.check.status.code);
  if (!e.check.status.ok()) j["why"] = e.check.status.message;
  j["poles"] = e.check.poles;
  j["readings"] = e.check.readings;
  j["distances_m"] = pair(e.check.distance_m);
  j["shift_m"] = pair(e.check.shift_m);
  j["shift_se_m"] = pair(e.check.shift_se_m);
  if (e.check.bias_replicas > 0) {
    j["fit_bias_m"] = pair(e.check.fit_bias_m);
    j["bias_replicas"] = e.check.bias_replicas;
  }
  j["test"] = watch::toString(e.test);
  if (e.test == watch::Test::absolute || e.test == watch::Test::change) {
    j["f"] = io::jsonNumber(e.f.statistic);
    j["dof"] = {e.f.dof1, e.f.dof2};
    j["p"] = io::jsonNumber(e.f.p);
    j["level"] = io::jsonNumber(e.level);
    j["exposure"] = io::jsonNumber(e.exposure);
    j["exceeds"] = e.exceeds;
    j["alarm"] = e.alarm;
  }
  j["record"] = e.record;
  j["model_version"] = e.model_version;
  return j;
}

ordered_json candidateJson(const CalibrationModel& m) {
  ordered_json j = {{"status", toString(m.status.code)}};
  if (!m.status.ok()) {
    j["why"] = m.status.message;
    return j;
  }
  j["alpha"] = m.model.bias.alpha;
  if (m.fitted_range_m) j["fitted_range_m"] = {m.fitted_range_m->first, m.fitted_range_m->second};
  j["warnings"] = m.warnings;
  return j;
}

ordered_json refitJson(const RefitRecord& r) {
  const watch::RefitEvent& e = r.event;
  ordered_json j = stretchJson(e.stretch);
  j["decided_at_scan"] = e.decided_at;
  if (e.candidate) j["candidate"] = candidateJson(*e.candidate);
  const watch::SwitchDecision& d = e.decision;
  j["differs"] = d.differs;
  if (d.test.tested) {
    j["difference_checks"] = d.test.checks;
    j["difference_f"] = io::jsonNumber(d.test.f.statistic);
    j["difference_p"] = io::jsonNumber(d.test.f.p);
  } else if (!d.test.why_not.empty()) {
    j["difference_not_tested"] = d.test.why_not;
  }
  j["determined"] = d.determined;
  j["plausible"] = d.plausible;
  j["switched"] = d.adopt;
  j["reason"] = d.reason;
  j["largest_se_m"] = io::jsonNumber(d.largest_se_m);
  if (d.difference.tested) {
    j["difference_distances_m"] = d.difference.distances_m;
    j["difference_m"] = d.difference.difference_m;
  }
  if (!r.model_file.empty()) j["model_file"] = r.model_file;
  j["model_version"] = e.model_version;
  return j;
}

ordered_json summaryJson(const WatchTimeline& t) {
  std::size_t decided = 0, baseline = 0, failed = 0, alarms = 0, exceeding = 0;
  double expected = 0.0, exposure = 0.0;
  for (const auto& c : t.checks) {
    if (!c.check.status.ok()) ++failed;
    if (c.test == watch::Test::baseline) ++baseline;
    if (c.test == watch::Test::absolute || c.test == watch::Test::change) {
      ++decided;
      expected += c.level;
      exposure += c.exposure;
      alarms += c.alarm ? 1 : 0;
      exceeding += c.exceeds ? 1 : 0;
    }
  }
  const watch::WatchState& s = t.final_state;
  return {{"scans", s.scans},
          {"travel_m", s.travel_m},
          {"driving_h", s.driving_h},
          {"checks", t.checks.size()},
          {"checks_failed", failed},
          {"baseline_checks", baseline},
          {"tests", decided},
          {"alarms", alarms},
          {"tests_exceeding", exceeding},
          {"switches", s.switches},
          {"exposure", exposure},
          {"exposure_unit", watch::toString(t.settings.false_alarms.unit)},
          {"expected_false_alarms", expected},
          {"level", watch::toString(s.level)},
          {"message", s.message}};
}

}  // namespace

ordered_json timelineJson(const WatchTimeline& t) {
  const watch::WatchSettings& w = t.settings;
  ordered_json j;
  j["format"] = "lidarcal-watch/1";
  j["input"] = t.input;
  j["model"] = t.model_file.empty() ? ordered_json(nullptr) : ordered_json(t.model_file);
  j["mode"] = watch::toString(w.mode);
  j["settings"] = {
      {"false_alarms", w.false_alarms.per_unit},
      {"per", watch::toString(w.false_alarms.unit)},
      {"check_every_m", w.check.every_m},
      {"baseline_checks", w.check.baseline_checks},
      {"record_checks", w.check.record_checks},
      {"min_sightings", w.check.min_sightings},
      {"landmark_radius_m", w.check.landmark_radius_m ? ordered_json(*w.check.landmark_radius_m)
                                                      : ordered_json(nullptr)},
      {"check_bias_replicas", w.check.bias_replicas}};
  if (t.injected)
    j["injected"] = {{"offset_m", t.injected->offset_m},
                     {"scale", t.injected->scale},
                     {"from_scan", t.injected->from_scan}};
  j["summary"] = summaryJson(t);
  j["checks"] = ordered_json::array();
  for (const auto& c : t.checks) j["checks"].push_back(checkJson(c));
  j["refits"] = ordered_json::array();
  for (const auto& r : t.refits) j["refits"].push_back(refitJson(r));
  return j;
}

std::size_t writeTimelinePlot(const std::filesystem::path& dir, const WatchTimeline& t) {
  std::size_t drawn = 0;
  std::ostringstream data;
  data << "# travel_m shift1_mm se1_mm shift2_mm se2_mm kind (0 baseline, 1 passed, 2 alarm)\n";
  for (const auto& c : t.checks) {
    if (!c.check.status.ok() || c.test == watch::Test::none) continue;
    const int kind = c.test == watch::Test::baseline ? 0 : c.exceeds ? 2 : 1;
    char line[200];
    std::snprintf(line, sizeof line, "%.3f %.3f %.3f %.3f %.3f %d\n", c.stretch.travel_m,
                  1000.0 * c.check.shift_m[0], 1000.0 * c.check.shift_se_m[0],
                  1000.0 * c.check.shift_m[1], 1000.0 * c.check.shift_se_m[1], kind);
    data << line;
    ++drawn;
  }
  if (drawn == 0) return 0;
  io::writeTextAtomically(dir / "timeline.dat", data.str());
  std::ostringstream gp;
  gp << "set terminal pngcairo size 1200,500 font \"DejaVu Sans,10\"\n"
        "set output \"timeline.png\"\nset grid\nset key outside right\n"
        "set xlabel \"travel [m]\"\nset ylabel \"shift of the corrected readings [mm]\"\n"
        "set title \"lidarcal watch: each check's shift at the reference distances (+- 1 SE)\"\n";
  for (const auto& r : t.refits)
    if (r.event.decision.adopt)
      gp << "set arrow from " << r.event.stretch.travel_m << ", graph 0 to "
         << r.event.stretch.travel_m << ", graph 1 nohead lc rgb \"#2a9d8f\" lw 2\n";
  gp << "plot \"timeline.dat\" using 1:($6==0?$2:1/0):3 with yerrorbars pt 6 lc rgb \"#999999\" "
        "title \"baseline\", \\\n"
        "  \"\" using 1:($6==1?$2:1/0):3 with yerrorbars pt 7 lc rgb \"#264653\" title \"passed, "
        "near\", \\\n"
        "  \"\" using 1:($6==1?$4:1/0):5 with yerrorbars pt 5 lc rgb \"#8ab17d\" title \"passed, "
        "far\", \\\n"
        "  \"\" using 1:($6==2?$2:1/0):3 with yerrorbars pt 9 ps 1.5 lc rgb \"#e63946\" title "
        "\"rejects the model\"\n";
  io::writeTextAtomically(dir / "timeline.gp", gp.str());
  return drawn;
}

std::string checkLine(const watch::CheckEvent& e) {
  if (!e.alarm) return "";
  char text[400];
  std::snprintf(text, sizeof text,
                "alarm at scan %zu (%.1f m): %s shift %+.1f +- %.1f mm at %.2f m, %+.1f +- %.1f "
                "mm at %.2f m (p = %.2g below the level %.2g)",
                e.decided_at, e.stretch.travel_m,
                e.test == watch::Test::absolute ? "the model does not fit this sensor:"
                                                : "the sensor changed:",
                1000.0 * e.check.shift_m[0], 1000.0 * e.check.shift_se_m[0], e.check.distance_m[0],
                1000.0 * e.check.shift_m[1], 1000.0 * e.check.shift_se_m[1], e.check.distance_m[1],
                e.f.p, e.level);
  return text;
}

std::string refitLine(const watch::RefitEvent& e) {
  if (!e.decision.adopt) return "";
  char text[160];
  std::snprintf(text, sizeof text, "switch at scan %zu (%.1f m) to model %llu: ", e.decided_at,
                e.stretch.travel_m, static_cast<unsigned long long>(e.model_version));
  return text + e.decision.reason;
}

std::string watchSummary(const WatchTimeline& t) {
  const ordered_json s = summaryJson(t);
  char text[600];
  std::snprintf(
      text, sizeof text,
      "%zu scans, %.1f m: %zu checks (%zu could not be made), %zu in the baseline, %zu tests, "
      "%zu alarms, %zu switches; false alarms expected at the rate set (%.3g per %s): %.3g\n"
      "state at the end: %s: %s\n",
      s["scans"].get<std::size_t>(), s["travel_m"].get<double>(), s["checks"].get<std::size_t>(),
      s["checks_failed"].get<std::size_t>(), s["baseline_checks"].get<std::size_t>(),
      s["tests"].get<std::size_t>(), s["alarms"].get<std::size_t>(),
      s["switches"].get<std::size_t>(), t.settings.false_alarms.per_unit,
      watch::toString(t.settings.false_alarms.unit), s["expected_false_alarms"].get<double>(),
      watch::toString(t.final_state.level), t.final_state.message.c_str());
  return text;
}

}  // namespace lidarcal::pipeline
