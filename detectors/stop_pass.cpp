// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/stop_pass.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/parallel.hpp"
#include "detectors/stop_radius.hpp"

namespace lidarcal::detectors {
namespace {

/// What a sequence keeps of a scan's detections: the detections (association, labels and
/// calibration need their centres and inliers), not the per-cluster diagnostics (a reason string
/// per cluster: about 2 KB per scan, 200 MB over 100,000 scans), with no spare capacity.
void compact(ScanDetections& d) {
  std::vector<ClusterSummary>().swap(d.clusters);
  d.detections.shrink_to_fit();
  for (auto& det : d.detections) det.inliers.shrink_to_fit();
}

/// Inlier points of a detection (sensor frame), kept while the radius is unknown.
std::vector<Eigen::Vector2d> arcOf(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                                   const Detection& d) {
  std::vector<Eigen::Vector2d> arc;
  arc.reserve(d.inliers.size());
  for (auto i : d.inliers)
    arc.emplace_back(cloud[static_cast<std::size_t>(i)].x, cloud[static_cast<std::size_t>(i)].y);
  return arc;
}

/// Detection configuration of a scan at `viewpoint`: the landmarks' world radius hints moved
/// into its sensor frame.
DetectionConfig configFor(const DetectionConfig& base, const std::vector<RadiusHint>& world,
                          const Pose2& viewpoint) {
  DetectionConfig cfg = base;
  for (const auto& h : world) {
    RadiusHint local = h;
    viewpoint.toSensor(h.x_m, h.y_m, local.x_m, local.y_m);
    cfg.radius_hints.push_back(local);
  }
  return cfg;
}

/// The radius unknown (first pass): thin far poles that no single arc determines are fitted
/// with the radius of the stop's scans pooled (stop_radius.hpp). Only objects no scan of the
/// stop found already: elsewhere the detections stay as they were.
void redetectWithPooledRadii(const std::vector<io::Scan>& loaded,
                             std::vector<ScanDetections>& found, const PassSetup& pass,
                             int threads) {
  std::vector<const pcl::PointCloud<pcl::PointXYZI>*> clouds;
  for (const auto& sc : loaded) clouds.push_back(sc.cloud.get());
  std::vector<RadiusHint> pooled;
  for (const RadiusHint& h : pooledStopRadii(clouds, pass.base)) {
    bool known = false;
    for (const auto& f : found)
      for (const auto& det : f.detections)
        known = known || std::hypot(det.centre_x_m - h.x_m, det.centre_y_m - h.y_m) <
                             det.radius_m + h.radius_m;
    if (!known) pooled.push_back(h);
  }
  if (!pooled.empty())
    parallelFor(loaded.size(), threads, [&](std::size_t k) {
      DetectionConfig cfg = configFor(pass.base, pass.hints_world, loaded[k].viewpoint);
      cfg.radius_hints.insert(cfg.radius_hints.end(), pooled.begin(), pooled.end());
      found[k] = detectScan(loaded[k], cfg);
    });
}

/// Folds one stop's tracks into a fingerprint of the association (the replay checks that it
/// meets the same stops and objects).
void fingerprint(std::uint64_t& h, std::size_t stop, const std::vector<TrackSerial>& tracks) {
  auto mix = [&h](std::uint64_t v) {  // FNV-1a over the value's bytes
    for (int b = 0; b < 8; ++b) h = (h ^ ((v >> (8 * b)) & 0xffu)) * 0x100000001b3ull;
  };
  mix(stop);
  mix(tracks.size());
  for (auto t : tracks) mix(t);
}

}  // namespace

void detectByStop(const ScanSource& source, const PassSetup& pass, int threads,
                  const std::function<void(StopBlock&)>& on_stop,
                  const std::function<void(std::size_t)>& on_scan) {
  const std::size_t scan_count = source.count;
  const StopOf& stop_of = source.stop_of;
  // Scans are loaded and detected a window at a time on `threads` threads (a scan's detection
  // depends on the scan and the pass's hints alone), then taken stop by stop in order. Memory:
  // the current stop and one window.
  const std::size_t window = 16 * static_cast<std::size_t>(std::max(threads, 1));
  std::vector<io::Scan> ahead;  // loaded and detected, not yet in a stop
  std::vector<ScanDetections> ahead_found;
  std::size_t ahead_first = 0;  // scan index of ahead[0]
  auto fill = [&](std::size_t first) {
    const std::size_t end = std::min(scan_count, first + window);
    for (std::size_t i = std::max<std::size_t>(first, 1); i < end; ++i)
      if (stop_of(i) < stop_of(i - 1))
        throw std::invalid_argument(
            "detectSequence: stop_of_scan must be non-decreasing (the scans of a stop "
            "consecutive)");
    ahead_first = first;
    ahead.assign(end - first, io::Scan{});
    ahead_found.assign(end - first, ScanDetections{});
    parallelFor(ahead.size(), threads, [&](std::size_t k) {
      ahead[k] = source.load(first + k);
      ahead_found[k] =
          detectScan(ahead[k], configFor(pass.base, pass.hints_world, ahead[k].viewpoint));
    });
  };
  std::vector<io::Scan> loaded;  // the scans of the current stop (one stop in memory)
  std::vector<ScanDetections> found;
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < scan_count; ++i) {
    if (i == 0 || i >= ahead_first + ahead.size()) fill(i);
    const std::size_t stop = stop_of(i);
    loaded.push_back(std::move(ahead[i - ahead_first]));
    found.push_back(std::move(ahead_found[i - ahead_first]));
    index.push_back(i);
    if (i + 1 < scan_count && stop_of(i + 1) == stop) continue;
    StopBlock block;
    block.stop = stop;
    if (pass.collect_arcs && !pass.base.landmark_radius_m && loaded.size() >= 2)
      redetectWithPooledRadii(loaded, found, pass, threads);
    for (std::size_t k = 0; k < loaded.size(); ++k) {
      const io::Scan& scan = loaded[k];
      ScanDetections& d = found[k];
      d.scan_index = index[k];
      d.stop = stop;
      if (pass.collect_arcs) {
        auto& arcs = block.arcs.emplace_back();
        for (const auto& det : d.detections) arcs.push_back(arcOf(*scan.cloud, det));
      }
      compact(d);
      block.scans.push_back(std::move(d));
      block.viewpoints.push_back(scan.viewpoint);
      if (on_scan) on_scan(index[k]);
    }
    block.loaded = &loaded;
    on_stop(block);
    loaded.clear();
    found.clear();
    index.clear();
  }
}

/// One stop's block through the association: stage 1 into `clusters` (cluster_of per
/// detection), then the linker; folds the tracks into `print` and returns each cluster's track.
std::vector<TrackSerial> linkBlock(const StopBlock& block, const AssociationConfig& cfg,
                                   StopLinker& linker, std::uint64_t& print, StopClusters& clusters,
                                   std::vector<std::vector<int>>& cluster_of) {
  std::vector<const ScanDetections*> ptrs;
  for (const auto& d : block.scans) ptrs.push_back(&d);
  const std::size_t conflicts = clusterStop(ptrs, block.viewpoints, cfg, clusters, &cluster_of);
  linker.moveTo(block.viewpoints.front());
  std::vector<TrackSerial> tracks = linker.add(clusters, conflicts);
  fingerprint(print, block.stop, tracks);
  return tracks;
}

/// Distinct stops among the first scan_count scans (stop_of non-decreasing).
std::size_t countStops(std::size_t scan_count, const StopOf& stop_of) {
  std::size_t n = 0;
  for (std::size_t i = 0, previous = 0; i < scan_count; ++i) {
    const std::size_t stop = stop_of(i);
    n += i == 0 || stop != previous;
    previous = stop;
  }
  return n;
}

/// Continuous motion: at least min_stops stops and more than half of them of one scan.
bool continuousStops(std::size_t scan_count, const StopOf& stop_of, int min_stops) {
  std::size_t stops = 0, single = 0, run = 0;
  for (std::size_t i = 0; i < scan_count; ++i) {
    ++run;
    if (i + 1 == scan_count || stop_of(i + 1) != stop_of(i)) {
      ++stops;
      single += run == 1;
      run = 0;
    }
  }
  return stops >= static_cast<std::size_t>(std::max(min_stops, 1)) && 2 * single > stops;
}

}  // namespace lidarcal::detectors
