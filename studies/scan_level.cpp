// SPDX-License-Identifier: BSD-3-Clause
#include "studies/scan_level.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "common/stats_util.hpp"
#include "detectors/sequence_detector.hpp"
#include "simulation/simulator.hpp"
#include "studies/trial.hpp"

namespace lidarcal::studies {
namespace {

Scene sceneOf(const std::vector<Cylinder>& layout, const PathSpec& path, const RangeModel& sensor,
              const ScanLevelConfig& c) {
  Scene scene;
  scene.name = "montecarlo";
  scene.sensor.beams = c.beams;
  scene.sensor.angle_min_rad = 0.0;
  scene.sensor.angle_increment_rad = 2.0 * kPi / c.beams;
  scene.sensor.range = sensor;
  scene.path = path;
  scene.landmarks = layout;
  return scene;
}

/// Detected landmark -> nearest true landmark within the gate, one to one (closest pairs first).
std::vector<int> matchLandmarks(const detectors::Association& a,
                                const std::vector<Cylinder>& layout, double gate_m) {
  struct Candidate {
    double d;
    std::size_t det, truth;
  };
  std::vector<Candidate> c;
  for (std::size_t i = 0; i < a.landmarks.size(); ++i)
    for (std::size_t t = 0; t < layout.size(); ++t) {
      const double d =
          std::hypot(a.landmarks[i].x_m - layout[t].x_m, a.landmarks[i].y_m - layout[t].y_m);
      if (d <= gate_m) c.push_back({d, i, t});
    }
  std::sort(c.begin(), c.end(), [](const Candidate& x, const Candidate& y) {
    return x.d != y.d ? x.d < y.d : (x.det != y.det ? x.det < y.det : x.truth < y.truth);
  });
  int max_id = 0;
  for (const auto& l : a.landmarks) max_id = std::max(max_id, l.id);
  std::vector<int> id(static_cast<std::size_t>(max_id) + 1, 0);
  std::vector<bool> used(layout.size(), false), done(a.landmarks.size(), false);
  for (const auto& x : c) {
    if (done[x.det] || used[x.truth]) continue;
    done[x.det] = used[x.truth] = true;
    id[static_cast<std::size_t>(a.landmarks[x.det].id)] = static_cast<int>(x.truth) + 1;
  }
  return id;
}

}  // namespace

void ScanLevelConfig::validate() const {
  if (beams < 8) throw std::invalid_argument("ScanLevelConfig: beams must be >= 8");
  if (!(match_distance_m > 0.0))
    throw std::invalid_argument("ScanLevelConfig: match_distance_m must be positive");
}

ScanLevelConfig scanLevelConfig(const TrialConfig& config) {
  ScanLevelConfig c;
  c.beams = config.scan_beams;
  return c;
}

namespace {

/// Sightings by the truth's own grouping: every beam on landmark t in scan i is one sighting of t.
void addTruthSightings(Draw& d, const std::vector<Cylinder>& layout,
                       const std::vector<TruthStop>& stops,
                       const simulation::SimulatedSequence& sim) {
  const auto& scans = sim.scans;
  const auto& stop_of_scan = sim.stop_of_scan;
  d.true_id.resize(layout.size() + 1);
  for (std::size_t l = 1; l <= layout.size(); ++l) d.true_id[l] = static_cast<int>(l);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    std::map<int, std::size_t> at;  // landmark -> sighting index in this scan
    const auto& cloud = *scans[i].scan.cloud;
    for (std::size_t b = 0; b < scans[i].truth.size(); ++b) {
      const io::TrueRange& t = scans[i].truth[b];
      if (t.target != io::TargetKind::landmark || !std::isfinite(cloud[b].x)) continue;
      auto [it, fresh] = at.try_emplace(t.target_id, d.obs.sightings.size());
      if (fresh) {
        Sighting s;
        s.stop = stop_of_scan[i];
        s.scan = i;
        s.landmark = t.target_id;
        const Cylinder& c = layout[static_cast<std::size_t>(t.target_id - 1)];
        Pose2 a = stops[s.stop].actual;
        double sx = 0.0, sy = 0.0;
        a.toSensor(c.x_m, c.y_m, sx, sy);
        s.bearing_rad = std::atan2(sy, sx);
        s.centre_range_m = std::hypot(sx, sy);
        s.radius_m = c.radius_m;
        d.obs.sightings.push_back(s);
        d.truth_m.emplace_back();
      }
      const double x = cloud[b].x, y = cloud[b].y;
      d.obs.sightings[it->second].beams.push_back(
          BeamReading{std::atan2(y, x), std::hypot(x, y), static_cast<std::uint32_t>(b)});
      d.truth_m[it->second].push_back(t.range_m);
    }
  }
}

/// Sightings of the detected landmarks: as detectors::toLandmarkObservations, from the scans in
/// memory, but within a scan in the detector's order, not by landmark (the study's stop-and-go
/// numbers in docs/results/montecarlo.md were measured in this order).
void addDetectedSightings(Draw& d, const detectors::SequenceDetections& det,
                          const simulation::SimulatedSequence& sim) {
  const auto& scans = sim.scans;
  const auto& stop_of_scan = sim.stop_of_scan;
  for (std::size_t i = 0; i < det.scans.size(); ++i) {
    const auto& sd = det.scans[i];
    const auto& ids = det.association.ids.at(i);
    const auto& cloud = *scans[i].scan.cloud;
    for (std::size_t j = 0; j < sd.detections.size(); ++j) {
      if (ids[j] <= 0) continue;
      const auto& det_j = sd.detections[j];
      Sighting s;
      s.stop = stop_of_scan[i];
      s.scan = i;
      s.landmark = ids[j];
      s.bearing_rad = det_j.bearing_rad;
      s.centre_range_m = det_j.range_m;
      s.radius_m = det_j.radius_m;
      std::vector<double> truth;
      const int true_id = static_cast<std::size_t>(ids[j]) < d.true_id.size()
                              ? d.true_id[static_cast<std::size_t>(ids[j])]
                              : 0;
      for (const auto idx : det_j.inliers) {
        const auto b = static_cast<std::size_t>(idx);
        const auto& p = cloud[b];
        if (!std::isfinite(p.x)) continue;
        s.beams.push_back(
            BeamReading{std::atan2(static_cast<double>(p.y), static_cast<double>(p.x)),
                        std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)),
                        static_cast<std::uint32_t>(b)});
        const io::TrueRange& t = scans[i].truth[b];
        // The truth of a beam counts only when it hit the landmark the detection was matched to.
        truth.push_back(t.target == io::TargetKind::landmark && t.target_id == true_id ? t.range_m
                                                                                       : kNaN);
      }
      if (s.beams.empty()) continue;
      d.obs.sightings.push_back(std::move(s));
      d.truth_m.push_back(std::move(truth));
    }
  }
}

}  // namespace

Draw drawScanLevel(const std::vector<Cylinder>& layout, const PathSpec& path,
                   const RangeModel& sensor, const ScanLevelConfig& config, std::uint64_t seed,
                   bool detect) {
  config.validate();
  const Scene scene = sceneOf(layout, path, sensor, config);
  const auto stops = simulation::planStops(scene, seed);
  const simulation::SimulatedSequence sim = simulation::simulateSequence(scene, stops, seed);

  Draw d;
  for (const auto& s : stops) {
    d.obs.commanded.push_back(s.commanded);
    d.actual.push_back(s.actual);
  }
  d.obs.range_min_m = sensor.range_min_m;
  d.obs.range_max_m = sensor.range_max_m;
  if (!layout.empty()) d.obs.landmark_radius_m = layout.front().radius_m;
  if (!detect) {
    addTruthSightings(d, layout, stops, sim);
    return d;
  }
  detectors::SequenceDetectionConfig dc;
  dc.detection.landmark_radius_m = d.obs.landmark_radius_m;  // known radius, as the paper assumes
  dc.threads = 1;                                            // the trials already run on every core
  const auto det = detectors::detectSequence(
      sim.scans.size(), [&](std::size_t i) { return sim.scans.at(i).scan; }, sim.stop_of_scan, dc);
  d.true_id = matchLandmarks(det.association, layout, config.match_distance_m);
  addDetectedSightings(d, det, sim);
  return d;
}

}  // namespace lidarcal::studies
