#include "detectors/sequence_detector.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "detectors/landmark_radius.hpp"

namespace lidarcal::detectors {

const char* toString(RadiusSource source) {
  switch (source) {
    case RadiusSource::known: return "known";
    case RadiusSource::estimated: return "estimated";
    case RadiusSource::none: return "none";
  }
  return "unknown";
}

void SequenceDetectionConfig::validate() const {
  detection.validate();
  association.validate();
  if (!(common_radius_tolerance >= 0.0 && common_radius_tolerance < 1.0))
    throw std::invalid_argument("SequenceDetectionConfig.common_radius_tolerance: must be in [0, 1)");
}

namespace {

/// Inlier points of a detection, kept while the radius is unknown (bounded by the detections).
std::vector<Eigen::Vector2d> arcOf(const pcl::PointCloud<pcl::PointXYZI>& cloud, const Detection& d) {
  std::vector<Eigen::Vector2d> arc;
  arc.reserve(d.inliers.size());
  for (auto i : d.inliers) arc.emplace_back(cloud[static_cast<std::size_t>(i)].x, cloud[static_cast<std::size_t>(i)].y);
  return arc;
}

void updateLandmarkPositions(SequenceDetections& r) {
  for (auto& l : r.association.landmarks) l.x_m = l.y_m = 0.0;
  for (std::size_t s = 0; s < r.scans.size(); ++s)
    for (std::size_t j = 0; j < r.scans[s].detections.size(); ++j) {
      const int id = r.association.ids[s][j];
      if (id == 0) continue;
      const Detection& d = r.scans[s].detections[j];
      double wx = 0.0, wy = 0.0;
      r.viewpoints[s].toWorld(d.centre_x_m, d.centre_y_m, wx, wy);
      auto& l = r.association.landmarks[static_cast<std::size_t>(id - 1)];
      l.x_m += wx, l.y_m += wy;
    }
  for (auto& l : r.association.landmarks) {
    l.x_m /= static_cast<double>(l.detections);
    l.y_m /= static_cast<double>(l.detections);
  }
}

/// Joint radius per landmark, then every detection's centre refitted with it.
void estimateRadii(SequenceDetections& r, const std::vector<std::vector<std::vector<Eigen::Vector2d>>>& arcs,
                   const DetectionConfig& cfg) {
  const std::size_t L = r.association.landmarks.size();
  std::vector<std::vector<std::pair<std::size_t, std::size_t>>> members(L);
  for (std::size_t s = 0; s < r.scans.size(); ++s)
    for (std::size_t j = 0; j < r.scans[s].detections.size(); ++j)
      if (const int id = r.association.ids[s][j]; id > 0) members[static_cast<std::size_t>(id - 1)].emplace_back(s, j);
  for (std::size_t l = 0; l < L; ++l) {
    std::vector<ArcObservation> obs;
    obs.reserve(members[l].size());
    for (const auto& [s, j] : members[l]) {
      const Detection& d = r.scans[s].detections[j];
      ArcObservation a;
      a.points = arcs[s][j];
      a.start = Circle2{d.centre_x_m, d.centre_y_m, d.radius_m};
      obs.push_back(std::move(a));
    }
    const RadiusEstimate est = estimateJointRadius(obs, cfg.radius_min_m, cfg.radius_max_m);
    if (est.status != FitStatus::ok) {
      ++r.radius_failures;
      continue;
    }
    r.association.landmarks[l].radius_m = est.radius_m;
    r.association.landmarks[l].radius_estimated = true;
    for (std::size_t k = 0; k < members[l].size(); ++k) {
      Detection& d = r.scans[members[l][k].first].detections[members[l][k].second];
      setCentre(d, est.centres[k]);
      d.radius_fixed = true;
      d.rms_m = circleRms(obs[k].points, est.centres[k]);
    }
  }
}

/// Second pass once radii are estimated: every scan again, with the landmarks expected in it as
/// radius hints, so that arcs too short for a free radius (3-4 returns) are fitted with the
/// estimated radius; then a fresh association.
void redetectWithRadii(SequenceDetections& r, const ScanLoader& load, const SequenceDetectionConfig& config,
                       const ProgressCallback& on_scan) {
  std::vector<RadiusHint> world;
  for (const auto& l : r.association.landmarks)
    if (l.radius_estimated) world.push_back(RadiusHint{l.x_m, l.y_m, l.radius_m});
  if (world.empty()) return;
  DetectionConfig cfg = config.detection;
  // Landmarks of one make (seed 000: cylinders of one radius): when every estimate agrees with
  // their median, clusters near no known landmark are fitted with that radius too.
  std::vector<double> radii;
  for (const auto& h : world) radii.push_back(h.radius_m);
  std::sort(radii.begin(), radii.end());
  const double median = radii[radii.size() / 2];
  if (radii.size() >= 2 && radii.front() >= median * (1.0 - config.common_radius_tolerance) &&
      radii.back() <= median * (1.0 + config.common_radius_tolerance)) {
    cfg.landmark_radius_m = median;
    r.common_radius_m = median;
  }
  for (std::size_t i = 0; i < r.scans.size(); ++i) {
    cfg.radius_hints.clear();
    for (const auto& h : world) {
      RadiusHint local = h;
      r.viewpoints[i].toSensor(h.x_m, h.y_m, local.x_m, local.y_m);
      cfg.radius_hints.push_back(local);
    }
    ScanDetections d = detectScan(load(i), cfg);
    d.scan_index = r.scans[i].scan_index;
    d.stop = r.scans[i].stop;
    r.scans[i] = std::move(d);
    if (on_scan) on_scan(r.scans.size() + i + 1, 2 * r.scans.size());
  }
  r.association = associate(r.scans, r.viewpoints, config.association);
  for (auto& l : r.association.landmarks) {
    // The radius came from the first pass when the landmark's detections were fitted with it.
    l.radius_estimated = r.common_radius_m.has_value();
    for (const auto& h : world)
      if (std::abs(h.radius_m - l.radius_m) < 1e-12) l.radius_estimated = true;
  }
}

}  // namespace

SequenceDetections detectSequence(std::size_t scan_count, const ScanLoader& load,
                                  const std::vector<std::size_t>& stop_of_scan, const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan) {
  config.validate();
  if (stop_of_scan.size() != scan_count) throw std::invalid_argument("detectSequence: one stop index per scan expected");
  SequenceDetections r;
  const bool known = config.detection.landmark_radius_m.has_value();
  r.known_radius_m = config.detection.landmark_radius_m;
  r.scans.reserve(scan_count);
  r.viewpoints.reserve(scan_count);
  std::vector<std::vector<std::vector<Eigen::Vector2d>>> arcs;  // only while the radius is unknown
  for (std::size_t i = 0; i < scan_count; ++i) {
    const io::Scan scan = load(i);
    ScanDetections d = detectScan(scan, config.detection);
    d.scan_index = i;
    d.stop = stop_of_scan[i];
    if (!known) {
      arcs.emplace_back();
      for (const auto& det : d.detections) arcs.back().push_back(arcOf(*scan.cloud, det));
    }
    r.viewpoints.push_back(scan.viewpoint);
    r.scans.push_back(std::move(d));
    if (on_scan) on_scan(i + 1, known ? scan_count : 2 * scan_count);
  }
  r.association = associate(r.scans, r.viewpoints, config.association);
  if (!known && !arcs.empty()) {
    // Arcs of detections that are not landmarks are not needed.
    for (std::size_t s = 0; s < arcs.size(); ++s)
      for (std::size_t j = 0; j < arcs[s].size(); ++j)
        if (r.association.ids[s][j] == 0) std::vector<Eigen::Vector2d>().swap(arcs[s][j]);
    estimateRadii(r, arcs, config.detection);
    std::vector<std::vector<std::vector<Eigen::Vector2d>>>().swap(arcs);
    updateLandmarkPositions(r);
    redetectWithRadii(r, load, config, on_scan);
  }
  if (on_scan && !known) on_scan(2 * scan_count, 2 * scan_count);  // no second pass without landmarks
  updateLandmarkPositions(r);

  std::size_t circles = 0;
  for (const auto& s : r.scans) circles += s.detections.size();
  if (r.association.landmarks.empty()) {
    r.radius_source = RadiusSource::none;
    r.note = circles == 0 ? "no circular object found in any scan: zero landmarks"
                          : std::to_string(circles) + " circle(s) found, but none seen in half the scans of " +
                                std::to_string(config.association.min_stops) +
                                " or more stops (capped at the number of stops): zero landmarks";
  } else {
    r.radius_source = known ? RadiusSource::known : RadiusSource::estimated;
    r.note = std::to_string(r.association.landmarks.size()) + " landmark(s) from " +
             std::to_string(r.association.assigned) + " of " + std::to_string(circles) + " circle detection(s)";
  }
  return r;
}

SequenceDetections detectSequence(const io::Sequence& sequence, const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan) {
  SequenceDetectionConfig cfg = config;
  if (!cfg.detection.landmark_radius_m && cfg.use_sequence_radius && sequence.meta.landmark_radius_m)
    cfg.detection.landmark_radius_m = sequence.meta.landmark_radius_m;
  return detectSequence(
      sequence.scans.size(), [&](std::size_t i) { return io::readScan(sequence.scans[i].path); }, sequence.stop_of_scan,
      cfg, on_scan);
}

std::vector<std::uint32_t> scanLabels(const SequenceDetections& result, std::size_t scan, std::size_t points) {
  std::vector<std::uint32_t> labels(points, 0u);
  const auto& dets = result.scans.at(scan).detections;
  for (std::size_t j = 0; j < dets.size(); ++j) {
    const int id = result.association.ids.at(scan).at(j);
    if (id <= 0) continue;
    for (auto i : dets[j].inliers) labels.at(static_cast<std::size_t>(i)) = static_cast<std::uint32_t>(id);
  }
  return labels;
}

}  // namespace lidarcal::detectors
