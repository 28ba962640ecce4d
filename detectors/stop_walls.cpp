// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/stop_walls.hpp"

#include <utility>

#include "detectors/wall_tracks.hpp"

namespace lidarcal::detectors {

std::vector<WallSighting> wallsAtStops(const io::Sequence& seq, const std::set<std::size_t>& stops,
                                       const ScanLoader& load, const DetectionConfig& detection) {
  std::vector<WallSighting> walls;
  WallConfig config;
  config.line.inlier_threshold_m = detection.threshold_m;
  config.threshold_per_m2 = detection.threshold_per_m2;
  for (std::size_t k : stops)
    for (std::size_t i : seq.stops[k].scans) {
      const io::Scan scan = load(i);
      for (WallSighting& ws : wallSightings(*scan.cloud, k, i, config))
        walls.push_back(std::move(ws));
    }
  labelWallSurfaces(walls);
  return walls;
}

}  // namespace lidarcal::detectors
