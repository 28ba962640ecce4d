#include "pipeline/collect_sightings.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "common/pose2.hpp"

namespace lidarcal::pipeline {

namespace {

/// A point (sensor frame) as its beam's reading: the point's direction is its beam's direction
/// (the sensor measures range along it). An intensity of 0 (what a scan without one reads as)
/// is none recorded.
BeamReading beamReading(float x, float y, float intensity, std::uint32_t beam) {
  return BeamReading{std::atan2(static_cast<double>(y), static_cast<double>(x)),
                     std::hypot(static_cast<double>(x), static_cast<double>(y)), beam,
                     intensity > 0.0f ? static_cast<double>(intensity) : std::nan("")};
}

/// Point i of a scan as a reading; nullopt without a return.
std::optional<BeamReading> pointReading(const io::Scan& scan, long i) {
  const auto& p = (*scan.cloud)[static_cast<std::size_t>(i)];
  if (!std::isfinite(p.x) || !std::isfinite(p.y)) return std::nullopt;
  return beamReading(p.x, p.y, p.intensity, static_cast<std::uint32_t>(i));
}

/// Angle from a to b, in [-pi, pi).
double turn(double a, double b) { return wrapAngle(b - a); }

/// A reading between a pole and its background, waiting for the check that nothing is there.
struct BesideCandidate {
  std::size_t sighting = 0;  ///< in LandmarkObservations::sightings
  bool front = false;        ///< before the sighting's first beam (else after its last)
  BeamReading reading;
};

/// A scan's returns in polar form, sorted by angle.
struct PolarScan {
  std::vector<double> angle_rad, range_m;
};

PolarScan polar(const io::Scan& scan) {
  std::vector<std::pair<double, double>> v;
  for (std::size_t i = 0; i < scan.cloud->size(); ++i)
    if (const auto r = pointReading(scan, static_cast<long>(i))) v.emplace_back(r->angle_rad, r->range_m);
  std::sort(v.begin(), v.end());
  PolarScan p;
  for (const auto& [a, r] : v) p.angle_rad.push_back(a), p.range_m.push_back(r);
  return p;
}

/// Whether a scan taken at `from` sees a surface at world point (x, y): one of the two returns
/// on each side of that direction reads its distance within `tolerance_m`.
bool seesPoint(const PolarScan& scan, const Pose2& from, double x, double y, double tolerance_m) {
  const std::size_t n = scan.angle_rad.size();
  if (n == 0) return false;
  const double dx = x - from.x_m, dy = y - from.y_m;
  const double rho = std::hypot(dx, dy), a = wrapAngle(std::atan2(dy, dx) - from.yaw_rad);
  const auto at = static_cast<long>(std::lower_bound(scan.angle_rad.begin(), scan.angle_rad.end(), a) - scan.angle_rad.begin());
  for (long k = at - 2; k < at + 2; ++k) {
    const auto j = static_cast<std::size_t>((k % static_cast<long>(n) + static_cast<long>(n)) % static_cast<long>(n));
    if (std::abs(scan.range_m[j] - rho) < tolerance_m) return true;
  }
  return false;
}

/// Keeps the candidates that no scan within `window` of theirs sees again (a surface behind the
/// pole is seen again from the same or a nearby pose; a mixed pixel's reading is random) and
/// puts them into their sightings.
void addLoneCandidates(const io::Sequence& seq, const detectors::ScanLoader& load, const detectors::DetectionConfig& dc,
                       std::vector<BesideCandidate> candidates, std::size_t window, LandmarkObservations& obs) {
  std::stable_sort(candidates.begin(), candidates.end(), [&](const BesideCandidate& a, const BesideCandidate& b) {
    return obs.sightings[a.sighting].scan < obs.sightings[b.sighting].scan;
  });
  std::map<std::size_t, PolarScan> cache;  // the scans within the window of the current candidate
  std::vector<bool> lone(candidates.size(), true);
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const std::size_t i = obs.sightings[candidates[c].sighting].scan;
    const std::size_t lo = i > window ? i - window : 0, hi = std::min(seq.scans.size(), i + window + 1);
    cache.erase(cache.begin(), cache.lower_bound(lo));
    const Pose2& at = seq.stops[seq.stopOf(i)].commanded;
    const BeamReading& r = candidates[c].reading;
    const double x = at.x_m + r.range_m * std::cos(at.yaw_rad + r.angle_rad);
    const double y = at.y_m + r.range_m * std::sin(at.yaw_rad + r.angle_rad);
    for (std::size_t o = lo; o < hi && lone[c]; ++o) {
      if (o == i) continue;
      auto it = cache.find(o);
      if (it == cache.end()) it = cache.emplace(o, polar(load(o))).first;
      lone[c] = !seesPoint(it->second, seq.stops[seq.stopOf(o)].commanded, x, y, 2.0 * dc.threshold(r.range_m));
    }
  }
  // Back to front, so that inserting at a sighting's front keeps the other candidates' places.
  for (std::size_t c = candidates.size(); c-- > 0;) {
    if (!lone[c]) continue;
    auto& beams = obs.sightings[candidates[c].sighting].beams;
    if (candidates[c].front)
      beams.insert(beams.begin(), candidates[c].reading);
    else
      beams.push_back(candidates[c].reading);
  }
}

}  // namespace

std::optional<BeamReading> readingBetweenPoleAndBackground(const io::Scan& scan, int edge, int step, double radius_m,
                                                           const detectors::DetectionConfig& config) {
  const long n = static_cast<long>(scan.cloud->size());
  if (n < 4) return std::nullopt;
  std::optional<BeamReading> r[4];
  for (long k = 0; k < 4; ++k) {
    r[k] = pointReading(scan, ((edge + k * step) % n + n) % n);
    if (!r[k]) return std::nullopt;
  }
  r[1]->beside = true;
  const double d1 = turn(r[0]->angle_rad, r[1]->angle_rad), d2 = turn(r[1]->angle_rad, r[2]->angle_rad),
               d3 = turn(r[2]->angle_rad, r[3]->angle_rad);
  for (double d : {d1, d3})
    if (!(d * d2 > 0.0) || std::abs(d - d2) > 0.25 * std::abs(d2)) return std::nullopt;
  const double pole = r[0]->range_m, y = r[1]->range_m;
  if (y < pole + radius_m + 2.0 * config.threshold(pole)) return std::nullopt;
  // The background along this beam: the ray (cos a, sin a) t meets the line p2 + s (p3 - p2).
  const double ux = std::cos(r[1]->angle_rad), uy = std::sin(r[1]->angle_rad);
  const double p2x = r[2]->range_m * std::cos(r[2]->angle_rad), p2y = r[2]->range_m * std::sin(r[2]->angle_rad);
  const double vx = r[3]->range_m * std::cos(r[3]->angle_rad) - p2x, vy = r[3]->range_m * std::sin(r[3]->angle_rad) - p2y;
  const double cross = ux * vy - uy * vx;
  const double along = std::abs(cross) > 1e-9 ? (p2x * vy - p2y * vx) / cross : r[2]->range_m;
  const double background = along > 0.0 ? std::min(along, r[2]->range_m) : r[2]->range_m;
  if (y > background - 3.0 * config.threshold(background)) return std::nullopt;
  return r[1];
}

LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const detectors::SequenceDetections& det,
                                            const SightingOptions& options) {
  return toLandmarkObservations(
      seq, det, [&seq](std::size_t i) { return io::readScan(seq.scans.at(i).path); }, options);
}

LandmarkObservations toLandmarkObservations(const io::Sequence& seq, const detectors::SequenceDetections& det,
                                            const detectors::ScanLoader& load, const SightingOptions& options) {
  LandmarkObservations obs;
  for (const auto& stop : seq.stops) obs.commanded.push_back(stop.commanded);
  if (det.known_radius_m) obs.landmark_radius_m = det.known_radius_m;
  obs.range_min_m = seq.meta.range_min_m.value_or(0.0);
  obs.range_max_m = seq.meta.range_max_m.value_or(1e9);
  // Point i is beam i only when every scan of the stop has the same number of points.
  std::vector<bool> same_beams(seq.stops.size(), true);
  for (std::size_t k = 0; k < seq.stops.size(); ++k)
    for (std::size_t i : seq.stops[k].scans)
      same_beams[k] = same_beams[k] && seq.scans[i].points == seq.scans[seq.stops[k].scans.front()].points;
  std::vector<BesideCandidate> beside;
  detectors::forEachScan(det, seq, load, [&](std::size_t i, const detectors::ScanDetections& sd, const std::vector<int>& ids) {
    bool any = false, kept_points = true;
    for (std::size_t j = 0; j < ids.size(); ++j)
      if (ids[j] > 0) any = true, kept_points = kept_points && sd.detections[j].inlier_xyi.size() == sd.detections[j].inliers.size();
    if (!any) return;
    // The inliers' coordinates kept by the detection, else the scan read again.
    if (options.mixed_pixel_candidates) kept_points = false;
    const io::Scan scan = kept_points ? io::Scan{} : load(i);
    for (std::size_t j = 0; j < sd.detections.size(); ++j) {
      if (ids[j] <= 0) continue;
      const auto& d = sd.detections[j];
      Sighting s;
      s.stop = seq.stopOf(i);
      s.scan = i;
      s.landmark = ids[j];
      s.bearing_rad = d.bearing_rad;
      s.centre_range_m = d.range_m;
      s.radius_m = d.radius_m;
      for (std::size_t k = 0; k < d.inliers.size(); ++k) {
        const auto idx = d.inliers[k];
        const float x = kept_points ? d.inlier_xyi[k][0] : (*scan.cloud)[static_cast<std::size_t>(idx)].x;
        const float y = kept_points ? d.inlier_xyi[k][1] : (*scan.cloud)[static_cast<std::size_t>(idx)].y;
        const float in = kept_points ? d.inlier_xyi[k][2] : (*scan.cloud)[static_cast<std::size_t>(idx)].intensity;
        if (!std::isfinite(x)) continue;
        s.beams.push_back(beamReading(x, y, in, same_beams[s.stop] ? static_cast<std::uint32_t>(idx) : kUnknownBeam));
      }
      if (s.beams.empty()) continue;
      if (options.mixed_pixel_candidates)
        for (const bool front : {true, false})
          if (auto r = readingBetweenPoleAndBackground(scan, front ? d.inliers.front() : d.inliers.back(), front ? -1 : 1,
                                                       d.radius_m, det.replay.detection)) {
            if (!same_beams[s.stop]) r->beam = kUnknownBeam;
            beside.push_back({obs.sightings.size(), front, *r});
          }
      obs.sightings.push_back(std::move(s));
    }
  });
  if (!beside.empty()) addLoneCandidates(seq, load, det.replay.detection, std::move(beside), options.persistence_scans, obs);
  // Within a scan by landmark id, not in the detector's order: a fit under a pose per scan sums
  // its terms in this order, and on a drive with a hidden effect the same sightings listed in
  // another order (a pole across the scan's seam moved from first to last) reached baselines
  // 440 nats apart (a yawed thin-pole drive). Their order is a function of what was seen.
  std::stable_sort(obs.sightings.begin(), obs.sightings.end(), [](const Sighting& a, const Sighting& b) {
    return a.scan != b.scan ? a.scan < b.scan : a.landmark < b.landmark;
  });
  return obs;
}

}  // namespace lidarcal::pipeline
