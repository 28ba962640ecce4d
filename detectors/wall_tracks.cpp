// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/wall_tracks.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "common/pose2.hpp"

namespace lidarcal::detectors {
namespace {

/// A surface while its sightings are gathered: sums for the circular mean of the normal and the
/// mean distance, and the scans it was seen in.
struct Track {
  double sin = 0.0, cos = 0.0, distance = 0.0;
  std::size_t n = 0;
  std::set<std::size_t> scans;
  double normal() const { return std::atan2(sin, cos); }
  double meanDistance() const { return distance / static_cast<double>(n); }
};

/// Labels the sightings `members` (all of one stop), ids from 1.
void labelStop(std::vector<WallSighting>& walls, std::vector<std::size_t> members,
               const WallTrackConfig& c) {
  // Longer pieces first (their normals are the steadier); ties broken by content, not by input
  // order.
  std::sort(members.begin(), members.end(), [&](std::size_t a, std::size_t b) {
    const WallSighting &x = walls[a], &y = walls[b];
    if (x.beams.size() != y.beams.size()) return x.beams.size() > y.beams.size();
    if (x.scan != y.scan) return x.scan < y.scan;
    return x.normal_rad != y.normal_rad ? x.normal_rad < y.normal_rad : x.distance_m < y.distance_m;
  });
  std::vector<Track> tracks;
  std::vector<std::size_t> track_of(walls.size(), 0);
  for (std::size_t i : members) {
    const WallSighting& w = walls[i];
    std::size_t best = tracks.size();
    double best_score = 2.0;  // normalised distance: both tolerances at 1
    for (std::size_t t = 0; t < tracks.size(); ++t) {
      if (tracks[t].scans.count(w.scan)) continue;
      const double angle = std::abs(wrapAngle(w.normal_rad - tracks[t].normal())) / c.max_angle_rad;
      const double distance = std::abs(w.distance_m - tracks[t].meanDistance()) / c.max_distance_m;
      if (angle > 1.0 || distance > 1.0) continue;
      if (angle + distance < best_score) best_score = angle + distance, best = t;
    }
    if (best == tracks.size()) tracks.emplace_back();
    Track& t = tracks[best];
    t.sin += std::sin(w.normal_rad);
    t.cos += std::cos(w.normal_rad);
    t.distance += w.distance_m;
    ++t.n;
    t.scans.insert(w.scan);
    track_of[i] = best;
  }
  // Two surfaces that the first sightings started apart (a wandering normal) but that agree and
  // were never seen in one scan are one.
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t a = 0; a < tracks.size() && !merged; ++a)
      for (std::size_t b = a + 1; b < tracks.size() && !merged; ++b) {
        Track &x = tracks[a], &y = tracks[b];
        if (y.n == 0 || x.n == 0 ||
            std::abs(wrapAngle(x.normal() - y.normal())) > c.max_angle_rad ||
            std::abs(x.meanDistance() - y.meanDistance()) > c.max_distance_m ||
            std::any_of(y.scans.begin(), y.scans.end(),
                        [&](std::size_t s) { return x.scans.count(s) > 0; }))
          continue;
        x.sin += y.sin, x.cos += y.cos, x.distance += y.distance, x.n += y.n;
        x.scans.insert(y.scans.begin(), y.scans.end());
        y = Track{};
        for (std::size_t& t : track_of)
          if (t == b) t = a;
        merged = true;
      }
  }
  // Ids by ascending mean normal direction (then distance); emptied tracks get none.
  std::vector<std::size_t> order;
  for (std::size_t t = 0; t < tracks.size(); ++t)
    if (tracks[t].n > 0) order.push_back(t);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const double na = tracks[a].normal(), nb = tracks[b].normal();
    return na != nb ? na < nb : tracks[a].meanDistance() < tracks[b].meanDistance();
  });
  std::vector<int> id(tracks.size());
  for (std::size_t k = 0; k < order.size(); ++k) id[order[k]] = static_cast<int>(k) + 1;
  for (std::size_t i : members) walls[i].wall = id[track_of[i]];
}

}  // namespace

std::vector<WallSighting> wallSightings(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                                        std::size_t stop, std::size_t scan,
                                        const WallConfig& config) {
  std::vector<WallSighting> out;
  for (const Wall& w : findWalls(cloud, config)) {
    WallSighting ws;
    ws.stop = stop;
    ws.scan = scan;
    ws.normal_rad = w.normal_rad;
    ws.distance_m = w.distance_m;
    ws.beams.reserve(w.inliers.size());
    for (const auto idx : w.inliers) {
      const auto& p = cloud[static_cast<std::size_t>(idx)];
      ws.beams.push_back(BeamReading{std::atan2(static_cast<double>(p.y), static_cast<double>(p.x)),
                                     std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)),
                                     static_cast<std::uint32_t>(idx)});
    }
    out.push_back(std::move(ws));
  }
  return out;
}

void WallTrackConfig::validate() const {
  if (!(max_angle_rad > 0.0 && max_angle_rad < 1.0))
    throw std::invalid_argument("WallTrackConfig.max_angle_rad: must be in (0, 1)");
  if (!(max_distance_m > 0.0) || !std::isfinite(max_distance_m))
    throw std::invalid_argument("WallTrackConfig.max_distance_m: must be > 0");
}

void labelWallSurfaces(std::vector<WallSighting>& walls, const WallTrackConfig& config) {
  config.validate();
  std::map<std::size_t, std::vector<std::size_t>> by_stop;
  for (std::size_t i = 0; i < walls.size(); ++i) by_stop[walls[i].stop].push_back(i);
  for (auto& [stop, members] : by_stop) labelStop(walls, std::move(members), config);
}

}  // namespace lidarcal::detectors
