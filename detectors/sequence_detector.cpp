// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/sequence_detector.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "common/errors.hpp"
#include "common/parallel.hpp"
#include "common/plural.hpp"

#include "detectors/detection_log.hpp"
#include "detectors/landmark_radius.hpp"
#include "detectors/stop_pass.hpp"
#include "detectors/stop_radius.hpp"

namespace lidarcal::detectors {

const char* toString(RadiusSource source) {
  switch (source) {
    case RadiusSource::known:
      return "known";
    case RadiusSource::estimated:
      return "estimated";
    case RadiusSource::none:
      return "none";
  }
  return "unknown";
}

void SequenceDetectionConfig::validate() const {
  detection.validate();
  association.validate();
  if (!(common_radius_tolerance >= 0.0 && common_radius_tolerance < 1.0))
    throw std::invalid_argument(
        "SequenceDetectionConfig.common_radius_tolerance: must be in [0, 1)");
  if (arcs_per_stop_cluster < 1)
    throw std::invalid_argument("SequenceDetectionConfig.arcs_per_stop_cluster: must be >= 1");
  if (!(continuous_drift_per_m >= 0.0) || !std::isfinite(continuous_drift_per_m))
    throw std::invalid_argument("SequenceDetectionConfig.continuous_drift_per_m: must be >= 0");
  if (arcs_per_landmark < 2)
    throw std::invalid_argument("SequenceDetectionConfig.arcs_per_landmark: must be >= 2");
  if (threads < 0)
    throw std::invalid_argument("SequenceDetectionConfig.threads: must be >= 0 (0: automatic)");
}

namespace {

/// The inliers' coordinates and intensities into each detection of a stop (kept scans).
void keepInlierPoints(StopBlock& block) {
  for (std::size_t i = 0; i < block.scans.size(); ++i) {
    const auto& cloud = *block.loaded->at(i).cloud;
    for (auto& d : block.scans[i].detections) {
      d.inlier_xyi.clear();
      d.inlier_xyi.reserve(d.inliers.size());
      for (auto k : d.inliers) {
        const auto& p = cloud[static_cast<std::size_t>(k)];
        d.inlier_xyi.push_back({p.x, p.y, p.intensity});
      }
    }
  }
}

/// A stop's detections and the track of each into the log; the log dropped when it cannot be
/// written (then forEachScan detects again: the log only saves time).
void logBlock(std::shared_ptr<DetectionLog>& log, const StopBlock& block,
              const std::vector<std::vector<int>>& cluster_of,
              const std::vector<TrackSerial>& tracks) {
  for (std::size_t i = 0; log && i < block.scans.size(); ++i) {
    std::vector<TrackSerial> of(cluster_of[i].size(), 0);
    for (std::size_t j = 0; j < of.size(); ++j)
      if (cluster_of[i][j] >= 0) of[j] = tracks.at(static_cast<std::size_t>(cluster_of[i][j]));
    if (!log->append(block.scans[i], of, pointsPrint(*block.loaded->at(i).cloud))) log.reset();
  }
}

/// One pass over the scans: the association stop by stop, and (as asked) the kept scans and an
/// even sample of each track's arcs.
struct Pass {
  std::uint64_t fingerprint = 0xcbf29ce484222325ull;
  std::map<TrackSerial, EvenSample<KeptArc>> arcs;  // per track alive (when collected)
  std::vector<ScanDetections> scans;                // when kept
  std::vector<Pose2> viewpoints;                    // when kept
  std::shared_ptr<DetectionLog> log;  // when not kept: every scan's detections and tracks
  TrackIds ids;
  Association association;
};

Pass runPass(const ScanSource& source, const PassSetup& pass, const SequenceDetectionConfig& config,
             bool keep_scans, const std::function<void(std::size_t)>& on_scan) {
  Pass p;
  const bool collect_arcs = pass.collect_arcs;
  StopLinker linker(config.association, countStops(source.count, source.stop_of));
  std::vector<std::vector<int>> cluster_of_scan;  // kept scans: cluster of each detection
  // kept scans: track of each of its stop's clusters
  std::vector<std::vector<TrackSerial>> track_of_scan;
  if (!keep_scans) p.log = DetectionLog::create();
  detectByStop(
      source, pass, threadsFor(config.threads),
      [&](StopBlock& block) {
        StopClusters clusters;
        std::vector<std::vector<int>> cluster_of;
        const std::vector<TrackSerial> tracks =
            linkBlock(block, config.association, linker, p.fingerprint, clusters, cluster_of);
        if (collect_arcs) {
          for (const auto& [from, into] : linker.merged()) {
            auto it = p.arcs.find(from);
            if (it == p.arcs.end()) continue;
            auto& sample = p.arcs.try_emplace(into, config.arcs_per_landmark).first->second;
            for (const auto& a : it->second.items()) sample.offer(a);
            p.arcs.erase(it);
          }
          // Up to arcs_per_stop_cluster arcs per cluster, spread evenly over its detections, into
          // an even sample of the track's arcs.
          std::vector<std::vector<std::pair<std::size_t, std::size_t>>> members(clusters.size());
          for (std::size_t i = 0; i < cluster_of.size(); ++i)
            for (std::size_t j = 0; j < cluster_of[i].size(); ++j)
              if (cluster_of[i][j] >= 0)
                members[static_cast<std::size_t>(cluster_of[i][j])].emplace_back(i, j);
          for (std::size_t c = 0; c < clusters.size(); ++c) {
            if (tracks[c] == 0) continue;
            auto& sample = p.arcs.try_emplace(tracks[c], config.arcs_per_landmark).first->second;
            const std::size_t n = members[c].size(), k = std::min(n, config.arcs_per_stop_cluster);
            for (std::size_t t = 0; t < k; ++t) {
              const auto [i, j] = members[c][t * n / k];
              const Detection& d = block.scans[i].detections[j];
              sample.offer(KeptArc{ArcObservation{std::move(block.arcs[i][j]),
                                                  Circle2{d.centre_x_m, d.centre_y_m, d.radius_m}},
                                   block.viewpoints[i]});
            }
          }
          for (auto t : linker.forgotten()) p.arcs.erase(t);
        }
        if (p.log) logBlock(p.log, block, cluster_of, tracks);
        if (keep_scans) {
          keepInlierPoints(block);
          for (auto& c : cluster_of)
            cluster_of_scan.push_back(std::move(c)), track_of_scan.push_back(tracks);
          for (auto& d : block.scans) p.scans.push_back(std::move(d));
          for (const auto& v : block.viewpoints) p.viewpoints.push_back(v);
        }
      },
      on_scan);
  if (p.log && !p.log->finish()) p.log.reset();
  p.association = linker.finish(p.ids);
  if (keep_scans)
    for (std::size_t i = 0; i < cluster_of_scan.size(); ++i)
      p.association.ids.push_back(landmarkIds(cluster_of_scan[i], track_of_scan[i], p.ids));
  return p;
}

/// Joint radius per landmark from the arcs kept for its track; the landmark's world position
/// from the refitted centres. Returns the hints for the second pass.
std::vector<RadiusHint> estimateRadii(SequenceDetections& r, const Pass& pass,
                                      const DetectionConfig& cfg) {
  const std::size_t L = r.association.landmarks.size();
  std::vector<std::vector<const KeptArc*>> arcs(L);
  for (const auto& [serial, sample] : pass.arcs)
    if (const int id = pass.ids.of(serial); id > 0)
      for (const auto& a : sample.items()) arcs[static_cast<std::size_t>(id - 1)].push_back(&a);
  std::vector<RadiusHint> world;
  for (std::size_t l = 0; l < L; ++l) {
    std::vector<ArcObservation> obs;
    obs.reserve(arcs[l].size());
    for (const KeptArc* a : arcs[l]) obs.push_back(a->arc);
    const RadiusEstimate est = estimateJointRadius(obs, cfg.radius_min_m, cfg.radius_max_m);
    if (est.status != FitStatus::ok) {
      ++r.radius_failures;
      continue;
    }
    auto& lm = r.association.landmarks[l];
    lm.radius_m = est.radius_m;
    lm.radius_estimated = true;
    double x = 0.0, y = 0.0;
    for (std::size_t k = 0; k < arcs[l].size(); ++k) {
      double wx = 0.0, wy = 0.0;
      arcs[l][k]->viewpoint.toWorld(est.centres[k].x_m, est.centres[k].y_m, wx, wy);
      x += wx, y += wy;
    }
    world.push_back(RadiusHint{x / static_cast<double>(arcs[l].size()),
                               y / static_cast<double>(arcs[l].size()), est.radius_m});
  }
  return world;
}

/// The pass's results into `r` (the arcs stay in `pass`).
void adopt(SequenceDetections& r, Pass& pass) {
  r.scans = std::move(pass.scans);
  r.viewpoints = std::move(pass.viewpoints);
  r.association = std::move(pass.association);
  r.replay.track_ids = pass.ids;
  r.replay.fingerprint = pass.fingerprint;
  r.log = std::move(pass.log);
}

}  // namespace

namespace {

SequenceDetections detectSequenceImpl(std::size_t scan_count, const ScanLoader& load,
                                      const StopOf& stop_of, const SequenceDetectionConfig& given,
                                      const ProgressCallback& on_scan) {
  given.validate();
  SequenceDetections r;
  SequenceDetectionConfig config = given;  // a copy: the association's reach for continuous motion
  r.continuous = continuousStops(scan_count, stop_of, config.continuous_min_stops);
  if (r.continuous && config.continuous_drift_per_m > 0.0) {
    config.association.drift_per_m = config.continuous_drift_per_m;
  }
  const bool known = config.detection.landmark_radius_m.has_value();
  r.known_radius_m = config.detection.landmark_radius_m;
  r.replay.detection = config.detection;
  r.replay.association = config.association;
  r.replay.threads = config.threads;
  const std::size_t total = known ? scan_count : 2 * scan_count;
  auto progress = [&](std::size_t offset) {
    return [&on_scan, offset, total](std::size_t i) {
      if (on_scan) on_scan(offset + i + 1, total);
    };
  };
  const ScanSource source{scan_count, load, stop_of};
  const std::vector<RadiusHint> no_hints;
  Pass first = runPass(source, PassSetup{config.detection, no_hints, !known}, config,
                       config.keep_scans, progress(0));
  adopt(r, first);
  if (!known && !r.association.landmarks.empty()) {
    // Second pass once radii are estimated: every scan again, with the landmarks expected in it
    // as radius hints, so that arcs too short for a free radius (3-4 returns) are fitted with
    // the estimated radius; then a fresh association.
    const std::vector<RadiusHint> world = estimateRadii(r, first, config.detection);
    if (!world.empty()) {
      DetectionConfig cfg = config.detection;
      // Landmarks of one make (Alhashimi et al. 2021: cylinders of one radius): when every estimate
      // agrees with their median, clusters near no known landmark are fitted with that radius too.
      std::vector<double> radii;
      for (const auto& h : world) radii.push_back(h.radius_m);
      std::sort(radii.begin(), radii.end());
      const double median = radii[radii.size() / 2];
      if (radii.size() >= 2 && radii.front() >= median * (1.0 - config.common_radius_tolerance) &&
          radii.back() <= median * (1.0 + config.common_radius_tolerance)) {
        cfg.landmark_radius_m = median;
        r.common_radius_m = median;
      }
      Pass second = runPass(source, PassSetup{cfg, world, false}, config, config.keep_scans,
                            progress(scan_count));
      adopt(r, second);
      r.replay.detection = cfg;
      r.replay.hints_world = world;
      for (auto& l : r.association.landmarks) {
        // The radius came from the first pass when the landmark's detections were fitted with it.
        l.radius_estimated = r.common_radius_m.has_value();
        for (const auto& h : world)
          if (std::abs(h.radius_m - l.radius_m) < 1e-12) l.radius_estimated = true;
      }
    }
  }
  if (on_scan && !known) on_scan(total, total);  // no second pass without landmarks

  const std::size_t circles = r.association.detections;
  if (r.association.landmarks.empty()) {
    r.radius_source = RadiusSource::none;
    r.note = circles == 0
                 ? "no circular object found in any scan: zero landmarks"
                 : plural(circles, "circle") + " found, but none seen in half the scans of " +
                       std::to_string(config.association.min_stops) +
                       " or more stops (capped at the number of stops): zero landmarks";
  } else {
    r.radius_source = known ? RadiusSource::known : RadiusSource::estimated;
    r.note = plural(r.association.landmarks.size(), "landmark") + " from " +
             std::to_string(r.association.assigned) + " of " + plural(circles, "circle detection");
  }
  return r;
}

/// The kept scans, loading each only when the visitor wants it.
void visitKept(const SequenceDetections& r, std::size_t scan_count, const ScanLoader& load,
               bool with_scan, const LoadedScanVisitor& visit, const ProgressCallback& on_scan) {
  if (r.scans.size() != scan_count)
    throw std::invalid_argument("forEachScan: the result holds " + std::to_string(r.scans.size()) +
                                " scans, not " + std::to_string(scan_count));
  const io::Scan none;
  for (std::size_t i = 0; i < scan_count; ++i) {
    visit(i, with_scan ? load(i) : none, r.scans[i], r.association.ids.at(i));
    if (on_scan) on_scan(i + 1, scan_count);
  }
}

/// The final pass read back from its log; each scan loaded once, and refused when its points
/// are not those detected.
void visitLogged(const SequenceDetections& r, std::size_t scan_count, const ScanLoader& load,
                 const LoadedScanVisitor& visit, const ProgressCallback& on_scan) {
  DetectionLog& log = *r.log;
  log.rewind();
  ScanDetections sd;
  std::vector<TrackSerial> tracks;
  std::uint64_t print = 0;
  for (std::size_t i = 0; i < scan_count; ++i) {
    if (!log.next(sd, tracks, print) || sd.scan_index != i)
      throw std::invalid_argument("forEachScan: scan " + std::to_string(i) +
                                  " is not among those detected");
    const io::Scan scan = load(i);
    if (!scan.cloud || pointsPrint(*scan.cloud) != print)
      throw DataError("scans", "scan " + std::to_string(i),
                      "changed while they were being read (other points than before)",
                      "leave the sequence untouched while lidarcal reads it, then run again");
    std::vector<int> ids(tracks.size(), 0);
    for (std::size_t j = 0; j < tracks.size(); ++j) ids[j] = r.replay.track_ids.of(tracks[j]);
    visit(i, scan, sd, ids);
    if (on_scan) on_scan(i + 1, scan_count);
  }
}

/// The final pass run again stop by stop: the same stops and objects give the same tracks, and
/// the ids found at the end of the first run.
void visitReplayed(const SequenceDetections& r, const ScanSource& source,
                   const LoadedScanVisitor& visit, const ProgressCallback& on_scan) {
  const auto& rp = r.replay;
  const std::size_t scan_count = source.count;
  StopLinker linker(rp.association, countStops(scan_count, source.stop_of));
  std::uint64_t print = 0xcbf29ce484222325ull;
  detectByStop(
      source, PassSetup{rp.detection, rp.hints_world, false}, threadsFor(rp.threads),
      [&](StopBlock& block) {
        StopClusters clusters;
        std::vector<std::vector<int>> cluster_of;
        const std::vector<TrackSerial> tracks =
            linkBlock(block, rp.association, linker, print, clusters, cluster_of);
        for (std::size_t i = 0; i < block.scans.size(); ++i)
          visit(block.scans[i].scan_index, block.loaded->at(i), block.scans[i],
                landmarkIds(cluster_of[i], tracks, rp.track_ids));
      },
      [&](std::size_t i) {
        if (on_scan) on_scan(i + 1, scan_count);
      });
  if (print != rp.fingerprint)
    throw DataError("scans", "",
                    "changed while they were being read (other objects at some stop than before)",
                    "leave the sequence untouched while lidarcal reads it, then run again");
}

/// Every scan with its detections: kept, logged or replayed, whichever the result allows.
void forEachScanImpl(const SequenceDetections& r, const ScanSource& source, bool with_scan,
                     const LoadedScanVisitor& visit, const ProgressCallback& on_scan) {
  if (!r.scans.empty() || source.count == 0)
    return visitKept(r, source.count, source.load, with_scan, visit, on_scan);
  if (r.log) return visitLogged(r, source.count, source.load, visit, on_scan);
  visitReplayed(r, source, visit, on_scan);
}

/// A visitor of detections as a visitor of loaded scans.
LoadedScanVisitor ignoringScan(const ScanVisitor& visit) {
  return [&visit](std::size_t i, const io::Scan&, const ScanDetections& d,
                  const std::vector<int>& ids) { visit(i, d, ids); };
}

/// A vector's entries as a StopOf, after checking its length.
StopOf stopsOf(const std::vector<std::size_t>& stop_of_scan, std::size_t scan_count) {
  if (stop_of_scan.size() != scan_count)
    throw std::invalid_argument("stop_of_scan: one stop index per scan expected");
  return [&stop_of_scan](std::size_t i) { return stop_of_scan[i]; };
}

ScanLoader loaderOf(const io::Sequence& sequence) {
  return [&sequence](std::size_t i) { return io::readScan(sequence.scans.path(i)); };
}

StopOf stopsOf(const io::Sequence& sequence) {
  return [&sequence](std::size_t i) { return sequence.stopOf(i); };
}

}  // namespace

SequenceDetections detectSequence(std::size_t scan_count, const ScanLoader& load,
                                  const std::vector<std::size_t>& stop_of_scan,
                                  const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan) {
  return detectSequenceImpl(scan_count, load, stopsOf(stop_of_scan, scan_count), config, on_scan);
}

SequenceDetections detectSequence(const io::Sequence& sequence,
                                  const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan) {
  return detectSequence(sequence, loaderOf(sequence), config, on_scan);
}

SequenceDetections detectSequence(const io::Sequence& sequence, const ScanLoader& load,
                                  const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan) {
  SequenceDetectionConfig cfg = config;
  if (!cfg.detection.landmark_radius_m && cfg.use_sequence_radius &&
      sequence.meta.landmark_radius_m)
    cfg.detection.landmark_radius_m = sequence.meta.landmark_radius_m;
  return detectSequenceImpl(sequence.scans.size(), load, stopsOf(sequence), cfg, on_scan);
}

void forEachScan(const SequenceDetections& r, std::size_t scan_count, const ScanLoader& load,
                 const std::vector<std::size_t>& stop_of_scan, const ScanVisitor& visit,
                 const ProgressCallback& on_scan) {
  forEachScanImpl(r, ScanSource{scan_count, load, stopsOf(stop_of_scan, scan_count)}, false,
                  ignoringScan(visit), on_scan);
}

void forEachScan(const SequenceDetections& result, const io::Sequence& sequence,
                 const ScanVisitor& visit, const ProgressCallback& on_scan) {
  forEachScan(result, sequence, loaderOf(sequence), visit, on_scan);
}

void forEachScan(const SequenceDetections& result, const io::Sequence& sequence,
                 const ScanLoader& load, const ScanVisitor& visit,
                 const ProgressCallback& on_scan) {
  forEachScanImpl(result, ScanSource{sequence.scans.size(), load, stopsOf(sequence)}, false,
                  ignoringScan(visit), on_scan);
}

void forEachLoadedScan(const SequenceDetections& result, std::size_t scan_count,
                       const ScanLoader& load, const std::vector<std::size_t>& stop_of_scan,
                       const LoadedScanVisitor& visit, const ProgressCallback& on_scan) {
  forEachScanImpl(result, ScanSource{scan_count, load, stopsOf(stop_of_scan, scan_count)}, true,
                  visit, on_scan);
}

void forEachLoadedScan(const SequenceDetections& result, const io::Sequence& sequence,
                       const LoadedScanVisitor& visit, const ProgressCallback& on_scan) {
  forEachScanImpl(result, ScanSource{sequence.scans.size(), loaderOf(sequence), stopsOf(sequence)},
                  true, visit, on_scan);
}

std::vector<std::uint32_t> scanLabels(const ScanDetections& detections, const std::vector<int>& ids,
                                      std::size_t points) {
  std::vector<std::uint32_t> labels(points, 0u);
  const auto& dets = detections.detections;
  for (std::size_t j = 0; j < dets.size(); ++j) {
    const int id = ids.at(j);
    if (id <= 0) continue;
    for (auto i : dets[j].inliers)
      labels.at(static_cast<std::size_t>(i)) = static_cast<std::uint32_t>(id);
  }
  return labels;
}

std::vector<std::uint32_t> scanLabels(const SequenceDetections& result, std::size_t scan,
                                      std::size_t points) {
  return scanLabels(result.scans.at(scan), result.association.ids.at(scan), points);
}

}  // namespace lidarcal::detectors
