// SPDX-License-Identifier: BSD-3-Clause
#include "simulation/landmark_level.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "common/rng.hpp"
#include "simulation/raycast.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::simulation {

namespace {

/// What the beams of a surface record as intensity: its own, or NaN (none recorded).
double recordedIntensity(const Cylinder& c) {
  return c.intensity > 0.0 ? c.intensity : std::nan("");
}

/// The stop's actual pose and the random streams of one scan.
struct ScanDraw {
  const Pose2& actual;
  std::size_t scan;
  std::mt19937_64& rng;
  std::mt19937_64& effect_rng;
  std::normal_distribution<double>& normal;
};

/// A landmark in view: the cylinder, its centre's distance and its true bearing in the sensor
/// frame.
struct InView {
  const Cylinder& c;
  double centre;        ///< metres
  double true_bearing;  ///< radians
};

/// Without beams: one reading of the landmark's nearest point along the (noisy) bearing, with
/// the true distance in `truth`; false when the reading leaves the sensor's window.
bool addCentralReading(const LandmarkLevelConfig& config, const InView& v, double e, ScanDraw& draw,
                       Sighting& s, std::vector<double>& truth) {
  const Cylinder& c = v.c;
  const double centre = v.centre;
  const double d = centre - c.radius_m;  // Alhashimi et al. 2021 eq. 2 minus the radius
  const double y = effectReading(config.model, config.effects, d,
                                 BeamContext{1.0, c.range_offset_m, draw.scan, c.intensity}, e,
                                 draw.effect_rng);  // eq. 3
  if (y < config.model.range_min_m || y > config.model.range_max_m) return false;
  s.beams.push_back(BeamReading{s.bearing_rad, y, 0, recordedIntensity(c)});
  truth.push_back(d);
  return true;
}

/// With beams: every grid beam that hits the landmark, its reading (the outermost ones may be
/// mixed pixels with what `background` shows behind), and its true distance in `truth`.
void addBeamReadings(const LandmarkLevelConfig& config, const Scene& background, const InView& v,
                     ScanDraw& draw, Sighting& s, std::vector<double>& truth) {
  const Cylinder& c = v.c;
  const double centre = v.centre, true_bearing = v.true_bearing;
  const Pose2& a = draw.actual;
  const double mount = config.mount_yaw_rad;
  const double half = std::asin(c.radius_m / centre);
  const double inc = config.angle_increment_rad;
  const double grid = config.angle_min_rad;
  const auto first = static_cast<long>(std::ceil((true_bearing - half - grid) / inc));
  const auto last = static_cast<long>(std::floor((true_bearing + half - grid) / inc));
  const long n = static_cast<long>(std::llround(2.0 * kPi / inc));
  auto rayAt = [&](long j) {
    const double w = a.yaw_rad + mount + grid + static_cast<double>(j) * inc;
    return Ray{a.x_m, a.y_m, std::cos(w), std::sin(w)};
  };
  // The beams that hit, then their readings (the outermost ones may be mixed pixels).
  std::vector<std::pair<long, double>> hits;  // (grid index, true distance or NaN)
  std::vector<double> beam_noise;
  for (long j = first; j <= last; ++j) {
    const auto t = intersectCircle(rayAt(j), c);
    hits.emplace_back(j, t ? *t : std::nan(""));
    // drawn for every grid beam, as before effects existed
    beam_noise.push_back(draw.normal(draw.rng));
  }
  long first_hit = last + 1, last_hit = first - 1;
  for (const auto& [j, t] : hits)
    if (std::isfinite(t)) {
      first_hit = std::min(first_hit, j);
      last_hit = std::max(last_hit, j);
    }
  for (std::size_t h = 0; h < hits.size(); ++h) {
    const auto [j, t] = hits[h];
    if (!std::isfinite(t)) continue;
    double back = std::nan("");
    for (long nb : {j - 1, j + 1}) {
      if ((nb == j - 1 && j != first_hit) || (nb == j + 1 && j != last_hit)) continue;
      const RayHit bh = castRay(background, rayAt(nb));
      if (bh.kind != io::TargetKind::none && bh.range_m > t &&
          (std::isnan(back) || bh.range_m < back))
        back = bh.range_m;
    }
    const double dm = mixedPixelDistance(config.effects, t, back, draw.effect_rng);
    const Ray ray = rayAt(j);
    const double perp = (c.y_m - a.y_m) * ray.dx - (c.x_m - a.x_m) * ray.dy;
    const double cos_inc =
        std::sqrt(std::max(0.0, 1.0 - (perp / c.radius_m) * (perp / c.radius_m)));
    const double y = effectReading(config.model, config.effects, dm,
                                   BeamContext{cos_inc, c.range_offset_m, draw.scan, c.intensity},
                                   beam_noise[h], draw.effect_rng);
    if (y < config.model.range_min_m || y > config.model.range_max_m) continue;
    const auto beam = static_cast<std::uint32_t>(((j % n) + n) % n);
    s.beams.push_back(
        BeamReading{wrapAngle(grid + static_cast<double>(j) * inc), y, beam, recordedIntensity(c)});
    truth.push_back(t);
  }
}

}  // namespace

LandmarkLevelSample simulateLandmarkLevel(const LandmarkLevelConfig& config, std::uint64_t seed) {
  LandmarkLevelSample out;
  Scene scene;
  scene.path = config.path;
  // eqs. 7-8, shared with the scan-level simulator
  out.stops = config.stops.empty() ? planStops(scene, seed) : config.stops;
  out.obs.range_min_m = config.model.range_min_m;
  out.obs.range_max_m = config.model.range_max_m;
  if (config.publish_radius && !config.landmarks.empty())
    out.obs.landmark_radius_m = config.landmarks.front().radius_m;
  for (const auto& s : out.stops) out.obs.commanded.push_back(s.commanded);

  std::normal_distribution<double> normal(0.0, 1.0);
  Scene background;  // what an edge beam may see behind its landmark (mixed pixels)
  background.landmarks = config.landmarks;
  background.walls = config.walls;
  const double mount = config.mount_yaw_rad;
  for (std::size_t k = 0; k < out.stops.size(); ++k) {
    const TruthStop& stop = out.stops[k];
    const Pose2& a = stop.actual;
    for (std::size_t i = 0; i < stop.scans; ++i) {
      const std::size_t scan = stop.first_scan + i;
      auto rng = makeRng(seed, scan + 1);
      auto effect_rng = effectRng(seed, scan);
      ScanDraw draw{a, scan, rng, effect_rng, normal};
      for (std::size_t l = 0; l < config.landmarks.size(); ++l) {
        const Cylinder& c = config.landmarks[l];
        const double dx = c.x_m - a.x_m, dy = c.y_m - a.y_m;
        const double centre = std::hypot(dx, dy);
        // Draw every number whether or not it is used, so streams stay aligned.
        const double v = normal(rng), e = normal(rng);
        if (centre <= c.radius_m) continue;
        Sighting s;
        s.stop = k;
        s.scan = scan;
        s.landmark = static_cast<int>(l) + 1;
        const double true_bearing = wrapAngle(std::atan2(dy, dx) - a.yaw_rad - mount);
        s.bearing_rad = wrapAngle(true_bearing + config.sigma_theta_rad * v);  // eq. 5
        s.centre_range_m = centre;
        s.radius_m = c.radius_m;
        std::vector<double> truth;
        if (!config.beams) {
          if (!addCentralReading(config, InView{c, centre, true_bearing}, e, draw, s, truth))
            continue;
        } else {
          addBeamReadings(config, background, InView{c, centre, true_bearing}, draw, s, truth);
          if (s.beams.empty()) continue;
        }
        out.obs.sightings.push_back(std::move(s));
        out.true_range_m.push_back(std::move(truth));
      }
    }
  }
  return out;
}

}  // namespace lidarcal::simulation
