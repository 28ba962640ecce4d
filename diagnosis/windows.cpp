// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/windows.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/plural.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::diagnosis {

std::string leadingWindow(LandmarkObservations& obs, std::size_t max_readings) {
  std::vector<std::size_t> per_stop(obs.commanded.size(), 0);
  std::size_t total = 0;
  for (const auto& s : obs.sightings)
    if (s.stop < per_stop.size()) {
      per_stop[s.stop] += s.beams.size();
      total += s.beams.size();
    }
  if (max_readings == 0 || total <= max_readings) return "";
  // Two stops at least, whatever they hold: a sequence diagnosis needs them.
  std::size_t stops = 0, kept = 0;
  while (stops < per_stop.size() && (stops < 2 || kept + per_stop[stops] <= max_readings))
    kept += per_stop[stops++];
  const std::size_t all_stops = obs.commanded.size();
  obs.commanded.resize(stops);
  obs.sightings.erase(std::remove_if(obs.sightings.begin(), obs.sightings.end(),
                                     [stops](const Sighting& s) { return s.stop >= stops; }),
                      obs.sightings.end());
  obs.walls.erase(std::remove_if(obs.walls.begin(), obs.walls.end(),
                                 [stops](const WallSighting& w) { return w.stop >= stops; }),
                  obs.walls.end());
  return "the first " + std::to_string(stops) + " of " + plural(all_stops, "stop") + ": " +
         std::to_string(kept) + " of " + plural(total, "landmark reading") + " (--max-readings " +
         std::to_string(max_readings) + ")";
}

void correctReadings(LandmarkObservations& obs, const ReadingCorrection& fix) {
  if (fix.inverter)
    for (auto& s : obs.sightings)
      for (auto& b : s.beams) b.range_m = fix.correct(b.range_m);
}

std::size_t busiestStop(const io::Sequence& seq) {
  std::size_t stop = 0;
  for (std::size_t k = 0; k < seq.stops.size(); ++k)
    if (seq.stops[k].scans.size() > seq.stops[stop].scans.size()) stop = k;
  return stop;
}

StaticScans staticScans(const io::Sequence& seq, std::size_t stop, const ReadingCorrection& fix,
                        const std::function<void(std::size_t)>& on_scan) {
  StaticScans s;
  const auto& scans = seq.stops.at(stop).scans;
  s.scans = scans.size();
  std::vector<std::size_t> counts;
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const io::Scan scan = io::readScan(seq.scans[scans[k]].path);
    counts.push_back(scan.cloud->size());
    // a covariate of the tails (dark surfaces)
    s.has_intensity = s.has_intensity || scan.has_intensity;
    for (const auto& p : *scan.cloud) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
      const double r = fix.correct(std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)));
      if (!(r > 0.0)) continue;
      s.readings.push_back({std::atan2(static_cast<double>(p.y), static_cast<double>(p.x)), r,
                            static_cast<std::uint32_t>(k),
                            scan.has_intensity ? static_cast<double>(p.intensity) : std::nan("")});
    }
    on_scan(k + 1);
  }
  std::sort(counts.begin(), counts.end());
  s.beams_per_scan = counts.empty() ? 0 : counts[counts.size() / 2];
  s.range_min_m = seq.meta.range_min_m.value_or(0.0);
  s.range_max_m = seq.meta.range_max_m.value_or(1e9);
  return s;
}

}  // namespace lidarcal::diagnosis
