// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/mixed_pixels.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "detectors/sightings.hpp"

namespace lidarcal::detectors {
namespace {

/// Angle from a to b, in [-pi, pi).
double turn(double a, double b) { return wrapAngle(b - a); }

}  // namespace

PolarScan polarScan(const io::Scan& scan) {
  std::vector<std::pair<double, double>> v;
  for (std::size_t i = 0; i < scan.cloud->size(); ++i)
    if (const auto r = pointReading(scan, static_cast<long>(i)))
      v.emplace_back(r->angle_rad, r->range_m);
  std::sort(v.begin(), v.end());
  PolarScan p;
  for (const auto& [a, r] : v) p.angle_rad.push_back(a), p.range_m.push_back(r);
  return p;
}

bool seesPoint(const PolarScan& scan, const Pose2& from, double x, double y, double tolerance_m) {
  const std::size_t n = scan.angle_rad.size();
  if (n == 0) return false;
  const double dx = x - from.x_m, dy = y - from.y_m;
  const double rho = std::hypot(dx, dy), a = wrapAngle(std::atan2(dy, dx) - from.yaw_rad);
  const auto at = static_cast<long>(
      std::lower_bound(scan.angle_rad.begin(), scan.angle_rad.end(), a) - scan.angle_rad.begin());
  for (long k = at - 2; k < at + 2; ++k) {
    const auto j = static_cast<std::size_t>((k % static_cast<long>(n) + static_cast<long>(n)) %
                                            static_cast<long>(n));
    if (std::abs(scan.range_m[j] - rho) < tolerance_m) return true;
  }
  return false;
}

void addLoneCandidates(const io::Sequence& seq, const ScanLoader& load, const DetectionConfig& dc,
                       std::vector<BesideCandidate> candidates, std::size_t window,
                       LandmarkObservations& obs) {
  std::stable_sort(candidates.begin(), candidates.end(),
                   [&](const BesideCandidate& a, const BesideCandidate& b) {
                     return obs.sightings[a.sighting].scan < obs.sightings[b.sighting].scan;
                   });
  std::map<std::size_t, PolarScan> cache;  // the scans within the window of the current candidate
  std::vector<bool> lone(candidates.size(), true);
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const std::size_t i = obs.sightings[candidates[c].sighting].scan;
    const std::size_t lo = i > window ? i - window : 0,
                      hi = std::min(seq.scans.size(), i + window + 1);
    cache.erase(cache.begin(), cache.lower_bound(lo));
    const Pose2& at = seq.stops[seq.stopOf(i)].commanded;
    const BeamReading& r = candidates[c].reading;
    const double x = at.x_m + r.range_m * std::cos(at.yaw_rad + r.angle_rad);
    const double y = at.y_m + r.range_m * std::sin(at.yaw_rad + r.angle_rad);
    for (std::size_t o = lo; o < hi && lone[c]; ++o) {
      if (o == i) continue;
      auto it = cache.find(o);
      if (it == cache.end()) it = cache.emplace(o, polarScan(load(o))).first;
      lone[c] = !seesPoint(it->second, seq.stops[seq.stopOf(o)].commanded, x, y,
                           2.0 * dc.threshold(r.range_m));
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

std::optional<BeamReading> readingBetweenPoleAndBackground(const io::Scan& scan, int edge, int step,
                                                           double radius_m,
                                                           const DetectionConfig& config) {
  const long n = static_cast<long>(scan.cloud->size());
  if (n < 4) return std::nullopt;
  std::optional<BeamReading> r[4];
  for (long k = 0; k < 4; ++k) {
    r[k] = pointReading(scan, ((edge + k * step) % n + n) % n);
    if (!r[k]) return std::nullopt;
  }
  r[1]->beside = true;
  const double d1 = turn(r[0]->angle_rad, r[1]->angle_rad),
               d2 = turn(r[1]->angle_rad, r[2]->angle_rad),
               d3 = turn(r[2]->angle_rad, r[3]->angle_rad);
  for (double d : {d1, d3})
    if (!(d * d2 > 0.0) || std::abs(d - d2) > 0.25 * std::abs(d2)) return std::nullopt;
  const double pole = r[0]->range_m, y = r[1]->range_m;
  if (y < pole + radius_m + 2.0 * config.threshold(pole)) return std::nullopt;
  // The background along this beam: the ray (cos a, sin a) t meets the line p2 + s (p3 - p2).
  const double ux = std::cos(r[1]->angle_rad), uy = std::sin(r[1]->angle_rad);
  const double p2x = r[2]->range_m * std::cos(r[2]->angle_rad),
               p2y = r[2]->range_m * std::sin(r[2]->angle_rad);
  const double vx = r[3]->range_m * std::cos(r[3]->angle_rad) - p2x,
               vy = r[3]->range_m * std::sin(r[3]->angle_rad) - p2y;
  const double cross = ux * vy - uy * vx;
  const double along = std::abs(cross) > 1e-9 ? (p2x * vy - p2y * vx) / cross : r[2]->range_m;
  const double background = along > 0.0 ? std::min(along, r[2]->range_m) : r[2]->range_m;
  if (y > background - 3.0 * config.threshold(background)) return std::nullopt;
  return r[1];
}

}  // namespace lidarcal::detectors
