// SPDX-License-Identifier: BSD-3-Clause
// lidarcal import BAG... --topic /front,/back [--sensor-names front,back] [--vehicle-frame F] -o
// RIG

#include <algorithm>
#include <cstdio>

#include "common/plural.hpp"
#include "io/bag_scans.hpp"
#include "pipeline/commands/cmd_rig.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    if (comma > start) out.push_back(text.substr(start, comma - start));
    start = comma + 1;
  }
  return out;
}

void runRigImport(const RigImportSettings& settings) {
  Progress progress("import (recordings x topics)", 1000);
  const RigImportResult r =
      importRig(settings, [&](double f) { progress.update(static_cast<std::size_t>(f * 1000.0)); });
  progress.finish();
  std::printf(
      "imported %zu sensors from %s into %s (a rig sequence: rig.json, scans.csv, one directory "
      "per sensor)\n",
      r.meta.sensors.size(), plural(settings.base.inputs.size(), "recording").c_str(),
      settings.base.out.string().c_str());
  std::printf(
      "| sensor | topic | frame | scans | beams | designed mounting (%s) "
      "|\n|---|---|---|---|---|---|\n",
      r.meta.vehicle_frame.empty() ? "vehicle frame unknown" : r.meta.vehicle_frame.c_str());
  for (std::size_t k = 0; k < r.meta.sensors.size(); ++k) {
    const io::RigSensorInfo& s = r.meta.sensors[k];
    const auto& w = r.written[k];
    char mount[160] = "none in /tf_static";
    if (s.mounting)
      std::snprintf(mount, sizeof mount, "x %.4f m, y %.4f m, yaw %.2f deg%s", s.mounting->x_m,
                    s.mounting->y_m, rad2deg(s.mounting->yaw_rad),
                    s.mounting->upside_down ? ", upside down" : "");
    std::string beams = w.min_beams == w.max_beams
                            ? std::to_string(w.max_beams)
                            : std::to_string(w.min_beams) + "-" + std::to_string(w.max_beams);
    std::printf("| %s | %s | %s | %zu | %s | %s |\n", s.name.c_str(), s.topic.c_str(),
                s.frame_id.c_str(), w.written, beams.c_str(), mount);
  }
  const io::BagPoseConfig& pose = settings.base.bag_pose;
  std::printf("  vehicle poses: %s; %s", r.meta.pose_source.c_str(),
              plural(r.stops, "stop").c_str());
  if (pose.kind != io::BagPoseConfig::Kind::none)
    std::printf(" (a new one at each recording and where the poses move beyond %.3g m or %.3g deg)",
                pose.still_m, rad2deg(pose.still_rad));
  std::printf("\n");
  for (const auto& note : r.notes) std::printf("  %s\n", note.c_str());
  if (!r.short_stops.empty()) {
    std::string where;
    for (const std::string& s : r.short_stops) where += (where.empty() ? "" : ", ") + s;
    std::fprintf(stderr,
                 "lidarcal: warning: %s: most stops hold one or two scans, the poses held while "
                 "they stay within %.3g m and %.3g deg: %s\n",
                 where.c_str(), pose.still_m, rad2deg(pose.still_rad),
                 io::shortStopsAdvice().c_str());
  }
}

}  // namespace lidarcal::pipeline
