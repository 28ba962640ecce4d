// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/summary.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

namespace lidarcal::pipeline {

SequenceSummary summarize(const io::Sequence& seq,
                          const std::function<void(std::size_t)>& on_scan) {
  SequenceSummary s;
  s.scans = seq.scans.size();
  s.stops = seq.stops.size();
  s.min_scans_per_stop = std::numeric_limits<std::size_t>::max();
  for (const auto& stop : seq.stops) {
    s.min_scans_per_stop = std::min(s.min_scans_per_stop, stop.scans.size());
    s.max_scans_per_stop = std::max(s.max_scans_per_stop, stop.scans.size());
  }
  s.min_step_m = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < seq.stops.size(); ++k) {
    const auto& a = seq.stops[k - 1].commanded;
    const auto& b = seq.stops[k].commanded;
    const double step = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    s.path_length_m += step;
    s.max_step_m = std::max(s.max_step_m, step);
    s.min_step_m = std::min(s.min_step_m, step);
  }
  if (seq.stops.size() < 2) s.min_step_m = 0.0;
  s.min_beams = std::numeric_limits<std::size_t>::max();
  s.min_range_m = std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (std::size_t i = 0; i < seq.scans.size(); ++i) {
    const io::Scan scan = io::readScan(seq.scans[i].path);
    s.min_beams = std::min(s.min_beams, scan.cloud->size());
    s.max_beams = std::max(s.max_beams, scan.cloud->size());
    s.points += scan.cloud->size();
    for (const auto& p : *scan.cloud) {
      if (!std::isfinite(p.x)) continue;
      const double r = std::hypot(p.x, p.y);
      ++s.returns;
      sum += r;
      s.min_range_m = std::min(s.min_range_m, r);
      s.max_range_m = std::max(s.max_range_m, r);
    }
    if (on_scan) on_scan(i + 1);
  }
  if (s.returns)
    s.mean_range_m = sum / static_cast<double>(s.returns);
  else
    s.min_range_m = 0.0;
  return s;
}

std::string toMarkdown(const io::Sequence& seq, const SequenceSummary& s) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(3);
  o << "# Sequence " << seq.dir.string() << "\n\n";
  o << "| item | value |\n|---|---|\n";
  o << "| scans | " << s.scans << " |\n";
  o << "| stops | " << s.stops << " (" << s.min_scans_per_stop
    << (s.min_scans_per_stop != s.max_scans_per_stop ? "-" + std::to_string(s.max_scans_per_stop)
                                                     : "")
    << (s.max_scans_per_stop == 1 ? " scan" : " scans") << " each) |\n";
  o << "| beams per scan | " << s.min_beams
    << (s.min_beams != s.max_beams ? "-" + std::to_string(s.max_beams) : "") << " |\n";
  o << "| returns | " << s.returns << " of " << s.points << " points ("
    << (s.points ? 100.0 * static_cast<double>(s.returns) / static_cast<double>(s.points) : 0.0)
    << " %) |\n";
  o << "| range of returns | " << s.min_range_m << " - " << s.max_range_m << " m (mean "
    << s.mean_range_m << " m) |\n";
  o << "| commanded path | " << s.path_length_m << " m, steps " << s.min_step_m << " - "
    << s.max_step_m << " m |\n";
  const auto& m = seq.meta;
  if (m.sensor_name) o << "| sensor | " << *m.sensor_name << " |\n";
  if (m.range_max_m)
    o << "| sensor range limits | " << m.range_min_m.value_or(0.0) << " - " << *m.range_max_m
      << " m |\n";
  else if (m.range_min_m)
    o << "| sensor range limits | from " << *m.range_min_m << " m (no upper limit recorded) |\n";
  if (seq.stops.size() < seq.scans.size() && !m.stop_starts.empty())
    o << "| stops begun by sequence.json | " << m.stop_starts.size()
      << " (stop_starts: recordings taken apart at one pose) |\n";
  if (m.landmark_radius_m) o << "| landmark radius | " << *m.landmark_radius_m << " m |\n";
  return o.str();
}

nlohmann::ordered_json toJson(const io::Sequence& seq, const SequenceSummary& s) {
  nlohmann::ordered_json j{
      {"sequence", seq.dir.string()},
      {"scans", s.scans},
      {"stops", s.stops},
      {"scans_per_stop", {{"min", s.min_scans_per_stop}, {"max", s.max_scans_per_stop}}},
      {"beams_per_scan", {{"min", s.min_beams}, {"max", s.max_beams}}},
      {"points", s.points},
      {"returns", s.returns},
      {"range_of_returns_m",
       {{"min", s.min_range_m}, {"max", s.max_range_m}, {"mean", s.mean_range_m}}},
      {"commanded_path_m", s.path_length_m},
      {"step_between_stops_m", {{"min", s.min_step_m}, {"max", s.max_step_m}}}};
  j["sequence_json"] = io::sequenceMetaJson(seq.meta);
  return j;
}

}  // namespace lidarcal::pipeline
