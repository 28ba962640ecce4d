// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/reports/ways_forward.hpp"

#include <algorithm>
#include <vector>

#include "calibration/span_walls.hpp"
#include "detectors/wall_tracks.hpp"
#include "io/pcd_scan.hpp"
#include "pipeline/reports/words.hpp"

namespace lidarcal::pipeline {
namespace {

/// Scans of a stop whose walls are enough to name them (the first ones; their noise averages out).
constexpr std::size_t kScansForWalls = 20;

constexpr const char* kReferenceFormat =
    "docs/FORMAT.md#wall-to-wall-spans, in \"Reference measurements\"";

}  // namespace

std::string wallsSeen(const io::Sequence& seq, std::size_t stop) {
  if (stop >= seq.stops.size()) return "none";
  detectors::WallConfig config;
  config.threshold_per_m2 = 0.005;  // the detection's default t(r) = 0.01 + 0.005 r^2
  std::vector<WallSighting> walls;
  const auto& scans = seq.stops[stop].scans;
  for (std::size_t k = 0; k < std::min(scans.size(), kScansForWalls); ++k) {
    const io::Scan scan = io::readScan(seq.scans.path(scans[k]));
    for (WallSighting& ws : detectors::wallSightings(*scan.cloud, stop, scans[k], config))
      walls.push_back(std::move(ws));
  }
  detectors::labelWallSurfaces(walls);
  return calibration::surfaceList(calibration::wallSurfaces(walls), stop);
}

std::string waysForward(const io::Sequence& seq, StatusCode code) {
  const bool one_place = seq.stops.size() == 1 || code == StatusCode::no_baseline;
  const std::string dir = seq.dir.string();
  if (one_place) {
    const std::string walls = wallsSeen(seq, 0);
    std::string text =
        "this recording was made from one place, which calibrates against what you measure there: "
        "`lidarcal calibrate " +
        dir +
        " --reference REF.json -o model.json` with wall-to-wall spans "
        "(a laser meter across the room between two walls the sensor sees on opposite sides";
    if (walls != "none")
      text += "; the walls stop 0 shows, by normal direction and distance as read: " + walls;
    text +=
        "), or tape distances to a pole or wall from 3 or more places (one recording each, "
        "imported with "
        "--stop-per-input) (" +
        std::string(kReferenceFormat) + "); `lidarcal diagnose " + dir +
        " -o DIR` criticises the range model on these scans; to self-calibrate, "
        "record poles from 3 or more stops along a line of at least 1 m, each stop with its own "
        "VIEWPOINT "
        "(see docs/ERRORS.md)";
    return text;
  }
  switch (code) {
    case StatusCode::too_few_stops:
      return "record 3 or more stops along a line, each with its own VIEWPOINT; or calibrate "
             "these " +
             plural(seq.stops.size(), "stop") +
             " against tape distances or wall-to-wall spans measured there "
             "(`lidarcal calibrate " +
             dir + " --reference REF.json`, " + kReferenceFormat + "); `lidarcal diagnose " + dir +
             " -o DIR` criticises the range model on them (see docs/ERRORS.md)";
    case StatusCode::no_usable_landmark:
    case StatusCode::too_few_observations:
    case StatusCode::joint_failed:
      return "`lidarcal detect " + dir +
             " -o DIR` shows which poles are found where; distances or wall-to-wall spans "
             "measured at some stops calibrate without triangulation (`--reference REF.json`, " +
             kReferenceFormat + ") (see docs/ERRORS.md)";
    default:
      return "see docs/ERRORS.md";
  }
}

}  // namespace lidarcal::pipeline
