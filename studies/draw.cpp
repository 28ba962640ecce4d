// SPDX-License-Identifier: BSD-3-Clause
#include "studies/draw.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>

#include "common/rng.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::studies {
namespace {
/// Random stream of the eq. 5 bearing noise: far above the simulator's streams (0 for the
/// poses, 1 + scan for the scans).
constexpr std::uint64_t kBearingStream = 0xbea7000000000000ULL;
}  // namespace

Draw drawLandmarkLevel(const std::vector<Cylinder>& landmarks, const PathSpec& path,
                       const RangeModel& sensor, double sigma_theta_rad, std::uint64_t seed,
                       bool rotate_beams) {
  simulation::LandmarkLevelConfig cfg;
  cfg.landmarks = landmarks;
  cfg.path = path;
  cfg.model = sensor;
  cfg.sigma_theta_rad = 0.0;  // exact bearings from the simulator; eq. 5 noise added per stop below
  cfg.beams = true;
  cfg.publish_radius = true;
  auto sample = simulation::simulateLandmarkLevel(cfg, seed);
  // One v_lk per (stop, landmark), from a stream the simulator does not use.
  const std::size_t L = landmarks.size();
  std::vector<double> v(sample.stops.size() * L);
  auto rng = makeRng(seed, kBearingStream);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (double& x : v) x = sigma_theta_rad * normal(rng);
  for (Sighting& s : sample.obs.sightings) {
    const double v_lk = v[s.stop * L + static_cast<std::size_t>(s.landmark - 1)];
    s.bearing_rad = wrapAngle(s.bearing_rad + v_lk);
    if (rotate_beams)
      for (BeamReading& b : s.beams) b.angle_rad = wrapAngle(b.angle_rad + v_lk);
  }
  Draw d;
  d.obs = std::move(sample.obs);
  d.truth_m = std::move(sample.true_range_m);
  d.true_id.resize(landmarks.size() + 1);
  for (std::size_t l = 1; l <= landmarks.size(); ++l) d.true_id[l] = static_cast<int>(l);
  for (const auto& s : sample.stops) d.actual.push_back(s.actual);
  return d;
}

std::vector<TruthReading> truthReadings(const Draw& draw) {
  std::vector<TruthReading> out;
  for (std::size_t i = 0; i < draw.obs.sightings.size(); ++i) {
    const Sighting& s = draw.obs.sightings[i];
    const int id = s.landmark > 0 && static_cast<std::size_t>(s.landmark) < draw.true_id.size()
                       ? draw.true_id[s.landmark]
                       : 0;
    if (id <= 0) continue;
    for (std::size_t j = 0; j < s.beams.size(); ++j) {
      const double t = draw.truth_m[i][j];
      if (!std::isfinite(t) || !std::isfinite(s.beams[j].range_m)) continue;
      out.push_back(TruthReading{s.stop, id, s.beams[j].beam, s.beams[j].range_m, t});
    }
  }
  return out;
}

LandmarkObservations averageScans(const LandmarkObservations& obs) {
  struct Beam {
    double angle = 0.0, sum = 0.0;
    int n = 0;
  };
  struct Group {
    double sin = 0.0, cos = 0.0, centre = 0.0, radius = 0.0;
    int n = 0;
    std::size_t first_scan = 0;
    std::map<std::uint32_t, Beam> beams;
  };
  std::map<std::pair<std::size_t, int>, Group> groups;  // (stop, landmark), ordered
  for (const auto& s : obs.sightings) {
    auto [it, fresh] = groups.try_emplace({s.stop, s.landmark});
    Group& g = it->second;
    if (fresh) g.first_scan = s.scan;
    g.sin += std::sin(s.bearing_rad);
    g.cos += std::cos(s.bearing_rad);
    g.centre += s.centre_range_m;
    g.radius += s.radius_m;
    ++g.n;
    for (const auto& b : s.beams) {
      if (!std::isfinite(b.range_m)) continue;
      Beam& a = g.beams[b.beam];
      a.angle = b.angle_rad;
      a.sum += b.range_m;
      ++a.n;
    }
  }
  LandmarkObservations out;
  out.commanded = obs.commanded;
  out.landmark_radius_m = obs.landmark_radius_m;
  out.range_min_m = obs.range_min_m;
  out.range_max_m = obs.range_max_m;
  for (const auto& [key, g] : groups) {
    Sighting s;
    s.stop = key.first;
    s.landmark = key.second;
    s.scan = key.first;  // one scan per stop after averaging
    s.bearing_rad = std::atan2(g.sin, g.cos);
    s.centre_range_m = g.centre / g.n;
    s.radius_m = g.radius / g.n;
    for (const auto& [beam, b] : g.beams)
      s.beams.push_back(BeamReading{b.angle, b.sum / b.n, beam});
    if (!s.beams.empty()) out.sightings.push_back(std::move(s));
  }
  return out;
}

}  // namespace lidarcal::studies
