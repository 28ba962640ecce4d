// SPDX-License-Identifier: BSD-3-Clause
#include "watch/pole_tracker.hpp"

#include <cmath>
#include <limits>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "detectors/sightings.hpp"
#include "io/raw_scan_cloud.hpp"

namespace lidarcal::watch {

namespace {
detectors::AssociationConfig validated(const detectors::AssociationConfig& c) {
  c.validate();
  return c;
}
}  // namespace

PoleTracker::PoleTracker(const detectors::DetectionConfig& detection,
                         const detectors::AssociationConfig& association)
    : detection_(detection),
      association_(validated(association)),
      // An endless stream of stops: min_stops is never capped by their number.
      linker_(association_, std::numeric_limits<std::size_t>::max()) {
  detection_.validate();
}

/// The sighting of detection `d` in `cloud`: its inliers as beam readings.
static PoleSighting sightingOf(const detectors::Detection& d,
                               const pcl::PointCloud<pcl::PointXYZI>& cloud, PoleId pole) {
  PoleSighting s;
  s.pole = pole;
  s.bearing_rad = d.bearing_rad;
  s.centre_range_m = d.range_m;
  s.radius_m = d.radius_m;
  s.beams.reserve(d.inliers.size());
  for (const auto idx : d.inliers) {
    const auto& p = cloud[static_cast<std::size_t>(idx)];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    s.beams.push_back(
        detectors::beamReading(p.x, p.y, p.intensity, static_cast<std::uint32_t>(idx)));
  }
  return s;
}

TrackedScan PoleTracker::track(const io::RawScan& scan, std::size_t index) {
  pcl::PointCloud<pcl::PointXYZI> cloud;
  io::toCloud(scan, cloud);
  detectors::ScanDetections det = detectors::detectScan(cloud, detection_);
  det.scan_index = index;
  det.stop = index;
  TrackedScan out;
  out.circles = det.detections.size();
  linker_.moveTo(scan.pose);
  if (det.detections.empty()) return out;
  detectors::StopClusters clusters;
  std::vector<std::vector<int>> cluster_of;
  const std::size_t conflicts =
      detectors::clusterStop({&det}, {scan.pose}, association_, clusters, &cluster_of);
  if (clusters.empty()) return out;
  const std::vector<detectors::TrackSerial> tracks = linker_.add(clusters, conflicts);
  out.merged = linker_.merged();
  for (std::size_t j = 0; j < det.detections.size(); ++j) {
    const int k = cluster_of[0][j];
    if (k < 0 || tracks[static_cast<std::size_t>(k)] == 0) continue;
    PoleSighting s = sightingOf(det.detections[j], cloud, tracks[static_cast<std::size_t>(k)]);
    if (!s.beams.empty()) out.poles.push_back(std::move(s));
  }
  return out;
}

}  // namespace lidarcal::watch
