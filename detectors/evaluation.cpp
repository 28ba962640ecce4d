// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace lidarcal::detectors {

ScanTruth makeScanTruth(const Truth& truth, std::size_t scan_index,
                        std::vector<io::TrueRange> beams,
                        const pcl::PointCloud<pcl::PointXYZI>& cloud) {
  if (beams.size() != cloud.size())
    throw std::invalid_argument("makeScanTruth: scan " + std::to_string(scan_index) + " has " +
                                std::to_string(cloud.size()) + " points but " +
                                std::to_string(beams.size()) + " true ranges");
  ScanTruth st;
  st.beams = std::move(beams);
  st.returned.resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    st.returned[i] = std::isfinite(cloud[i].x) && std::isfinite(cloud[i].y);
  bool found = false;
  for (const auto& s : truth.stops)
    if (scan_index >= s.first_scan && scan_index < s.first_scan + s.scans) {
      st.sensor = s.actual;
      found = true;
    }
  if (!found)
    throw std::invalid_argument("makeScanTruth: scan " + std::to_string(scan_index) +
                                " is in no truth stop");
  st.sensor.yaw_rad += truth.scene.sensor.mount_yaw_rad;
  return st;
}

namespace {

struct BinSums {
  std::size_t observable = 0, detected = 0, n = 0, n_free = 0;
  double centre2 = 0, bearing2 = 0, range = 0, range2 = 0, free = 0, free2 = 0, radius = 0;
};

std::size_t binOf(const std::vector<double>& edges, double d) {
  for (std::size_t b = 0; b + 1 < edges.size(); ++b)
    if (d >= edges[b] && d < edges[b + 1]) return b;
  return edges.size();  // outside every bin
}

/// Per landmark (1-based): the beams on it do not form one run, or a beam next to the run hits
/// something nearer (the landmark is partly hidden behind another object).
std::vector<bool> partlyHidden(const ScanTruth& t, std::size_t landmarks) {
  const std::size_t n = t.beams.size();
  std::vector<bool> hidden(landmarks + 1, false);
  auto on = [&](std::size_t i, std::size_t l) {
    return t.beams[i].target == io::TargetKind::landmark &&
           t.beams[i].target_id == static_cast<int>(l);
  };
  for (std::size_t l = 1; l <= landmarks && n > 0; ++l) {
    std::size_t starts = 0, first = n;
    for (std::size_t i = 0; i < n; ++i)
      if (on(i, l) && !on((i + n - 1) % n, l)) ++starts, first = i;
    if (starts == 0) continue;  // not hit (or hit by every beam)
    if (starts > 1) {
      hidden[l] = true;
      continue;
    }
    std::size_t last = first;
    while (on((last + 1) % n, l) && (last + 1) % n != first) last = (last + 1) % n;
    const std::size_t before = (first + n - 1) % n, after = (last + 1) % n;
    auto nearer = [&](std::size_t nb, std::size_t end) {
      return t.beams[nb].target != io::TargetKind::none &&
             t.beams[nb].range_m < t.beams[end].range_m;
    };
    hidden[l] = nearer(before, first) || nearer(after, last);
  }
  return hidden;
}

/// The target a detection's inliers voted for most: its kind and id (0 when none).
std::pair<io::TargetKind, int> votedTarget(const Detection& d, const ScanTruth& t) {
  std::map<std::pair<int, int>, std::size_t> votes;
  for (auto i : d.inliers) {
    const auto& b = t.beams.at(static_cast<std::size_t>(i));
    ++votes[{static_cast<int>(b.target), b.target_id}];
  }
  std::pair<int, int> best{0, 0};
  std::size_t best_n = 0;
  for (const auto& [k, n] : votes)
    if (n > best_n) best = k, best_n = n;
  return {static_cast<io::TargetKind>(best.first), best.second};
}

/// The true landmarks in one scan's sensor frame: position and distance, index 1..L.
struct LandmarksSeen {
  std::vector<double> x, y, dist;
};

LandmarksSeen landmarksInSensorFrame(const ScanTruth& t, const std::vector<Cylinder>& landmarks) {
  const std::size_t L = landmarks.size();
  LandmarksSeen seen{std::vector<double>(L + 1), std::vector<double>(L + 1),
                     std::vector<double>(L + 1)};
  for (std::size_t l = 1; l <= L; ++l) {
    t.sensor.toSensor(landmarks[l - 1].x_m, landmarks[l - 1].y_m, seen.x[l], seen.y[l]);
    seen.dist[l] = std::hypot(seen.x[l], seen.y[l]);
  }
  return seen;
}

/// Adds the errors of a true detection of landmark l (radius R, reading bias f) to its bin.
void addDetectionErrors(BinSums& bs, const Detection& d, const LandmarksSeen& seen, std::size_t l,
                        double R, const BiasPolynomial& f) {
  const double expected = f(seen.dist[l] - R) + R;
  ++bs.n;
  bs.centre2 += std::pow(d.centre_x_m - seen.x[l], 2) + std::pow(d.centre_y_m - seen.y[l], 2);
  bs.bearing2 += std::pow(wrapAngle(d.bearing_rad - std::atan2(seen.y[l], seen.x[l])), 2);
  bs.range += d.range_m - expected;
  bs.range2 += std::pow(d.range_m - expected, 2);
  bs.radius += d.radius_m - R;
  if (d.free_status == FitStatus::ok) {
    ++bs.n_free;
    bs.free += d.free_radius_m - R;
    bs.free2 += std::pow(d.free_radius_m - R, 2);
  }
}

/// Everything evaluateDetections accumulates over the scans.
struct Tally {
  DetectionEvaluation ev;
  std::vector<BinSums> bins;
  /// (id, truth landmark or 0) per detection with an id
  std::vector<std::pair<int, int>> id_truth;
};

/// One scan to score: its detections with their ids (null: not associated), its truth and
/// where its landmarks lie in the sensor frame.
struct ScoredScan {
  const ScanDetections& found;
  const std::vector<int>* ids;
  const ScanTruth& truth;
  const LandmarksSeen& seen;
};

/// Scores the detections of a scan against its truth; returns which landmarks were detected.
std::vector<bool> scoreDetections(Tally& tally, const ScoredScan& scan, const Scene& scene,
                                  const EvaluationConfig& cfg) {
  const ScanTruth& t = scan.truth;
  const LandmarksSeen& seen = scan.seen;
  const std::size_t L = scene.landmarks.size();
  std::vector<bool> detected(L + 1, false);
  for (std::size_t j = 0; j < scan.found.detections.size(); ++j) {
    const Detection& d = scan.found.detections[j];
    const int id = scan.ids ? (*scan.ids)[j] : 0;
    if (scan.ids && id == 0) continue;
    ++tally.ev.detections;
    const auto [kind, target] = votedTarget(d, t);
    int truth_l = 0;
    if (kind == io::TargetKind::landmark && target >= 1 && static_cast<std::size_t>(target) <= L) {
      truth_l = target;
      ++tally.ev.true_positives;
      const auto l = static_cast<std::size_t>(truth_l);
      detected[l] = true;
      const std::size_t b = binOf(cfg.range_edges_m, seen.dist[l]);
      if (b < tally.bins.size())
        addDetectionErrors(tally.bins[b], d, seen, l, scene.landmarks[l - 1].radius_m,
                           scene.sensor.range.bias);
    } else {
      ++tally.ev.false_positives;
      if (kind == io::TargetKind::clutter) ++tally.ev.false_on_clutter;
      if (kind == io::TargetKind::wall) ++tally.ev.false_on_walls;
    }
    if (scan.ids) tally.id_truth.emplace_back(id, truth_l);
  }
  return detected;
}

/// Counts the landmarks of one scan that were observable (enough beams on them, not partly
/// hidden) and which of them were detected.
void countObservable(Tally& tally, const ScanTruth& t, const LandmarksSeen& seen,
                     const std::vector<bool>& detected, std::size_t L,
                     const EvaluationConfig& cfg) {
  std::vector<std::size_t> beams_on(L + 1, 0);
  for (std::size_t i = 0; i < t.beams.size(); ++i)
    if (t.returned[i] && t.beams[i].target == io::TargetKind::landmark &&
        t.beams[i].target_id >= 1 && static_cast<std::size_t>(t.beams[i].target_id) <= L)
      ++beams_on[static_cast<std::size_t>(t.beams[i].target_id)];
  const std::vector<bool> hidden = partlyHidden(t, L);
  DetectionEvaluation& ev = tally.ev;
  for (std::size_t l = 1; l <= L; ++l) {
    if (beams_on[l] < static_cast<std::size_t>(cfg.min_beams)) continue;
    if (hidden[l]) {
      ++ev.partly_hidden;
      if (detected[l]) ++ev.partly_hidden_detected;
      continue;
    }
    ++ev.observable;
    if (detected[l]) ++ev.detected;
    const std::size_t b = binOf(cfg.range_edges_m, seen.dist[l]);
    if (b < tally.bins.size()) {
      ++tally.bins[b].observable;
      if (detected[l]) ++tally.bins[b].detected;
    }
  }
}

/// Ids: each id's truth landmark by majority; split ids (two ids on one landmark) and
/// detections whose id's landmark is not theirs.
void scoreIds(DetectionEvaluation& ev, const Association& association,
              const std::vector<std::pair<int, int>>& id_truth, std::size_t L) {
  ev.ids = association.landmarks.size();
  std::vector<std::map<int, std::size_t>> votes(ev.ids);
  for (const auto& [id, l] : id_truth)
    if (l > 0) ++votes[static_cast<std::size_t>(id - 1)][l];
  ev.truth_of_id.assign(ev.ids, 0);
  std::vector<bool> taken(L + 1, false);
  for (std::size_t k = 0; k < ev.ids; ++k) {
    std::size_t best_n = 0;
    for (const auto& [l, n] : votes[k])
      if (n > best_n) ev.truth_of_id[k] = l, best_n = n;
    const int l = ev.truth_of_id[k];
    if (l > 0) {
      if (taken[static_cast<std::size_t>(l)]) ++ev.split_ids;
      taken[static_cast<std::size_t>(l)] = true;
    }
  }
  ev.with_id = id_truth.size();
  for (const auto& [id, l] : id_truth)
    if (l == 0 || ev.truth_of_id[static_cast<std::size_t>(id - 1)] != l) ++ev.wrong_id;
  ev.purity = ev.with_id ? 1.0 - double(ev.wrong_id) / double(ev.with_id) : 1.0;
}

RangeBin summariseBin(const BinSums& s, double lo_m, double hi_m) {
  RangeBin r;
  r.lo_m = lo_m;
  r.hi_m = hi_m;
  r.observable = s.observable;
  r.detected = s.detected;
  r.detections = s.n;
  r.free_radii = s.n_free;
  if (s.n) {
    const double n = double(s.n);
    r.centre_rms_m = std::sqrt(s.centre2 / n);
    r.bearing_rms_rad = std::sqrt(s.bearing2 / n);
    r.range_bias_m = s.range / n;
    r.range_rms_m = std::sqrt(s.range2 / n);
    r.radius_bias_m = s.radius / n;
  }
  if (s.n_free) {
    r.free_radius_bias_m = s.free / double(s.n_free);
    r.free_radius_rms_m = std::sqrt(s.free2 / double(s.n_free));
  }
  return r;
}

}  // namespace

DetectionEvaluation evaluateDetections(const std::vector<ScanDetections>& scans,
                                       const Association* association,
                                       const std::vector<ScanTruth>& truth,
                                       const Truth& scene_truth, const EvaluationConfig& cfg) {
  if (truth.size() != scans.size())
    throw std::invalid_argument("evaluateDetections: one ScanTruth per scan expected");
  if (association && association->ids.size() != scans.size())
    throw std::invalid_argument("evaluateDetections: association of another scan list");
  const Scene& scene = scene_truth.scene;
  const std::size_t L = scene.landmarks.size();
  Tally tally;
  tally.ev.scans = scans.size();
  tally.bins.resize(cfg.range_edges_m.size() > 1 ? cfg.range_edges_m.size() - 1 : 0);
  for (std::size_t s = 0; s < scans.size(); ++s) {
    const LandmarksSeen seen = landmarksInSensorFrame(truth[s], scene.landmarks);
    const ScoredScan scored{scans[s], association ? &association->ids[s] : nullptr, truth[s], seen};
    const std::vector<bool> detected = scoreDetections(tally, scored, scene, cfg);
    countObservable(tally, truth[s], seen, detected, L, cfg);
  }
  DetectionEvaluation& ev = tally.ev;
  ev.precision = ev.detections ? double(ev.true_positives) / double(ev.detections) : 1.0;
  ev.recall = ev.observable ? double(ev.detected) / double(ev.observable) : 1.0;
  if (association) scoreIds(ev, *association, tally.id_truth, L);
  for (std::size_t b = 0; b < tally.bins.size(); ++b)
    ev.bins.push_back(summariseBin(tally.bins[b], cfg.range_edges_m[b], cfg.range_edges_m[b + 1]));
  return ev;
}

}  // namespace lidarcal::detectors
