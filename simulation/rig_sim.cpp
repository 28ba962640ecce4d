// SPDX-License-Identifier: BSD-3-Clause
#include "simulation/rig_sim.hpp"

#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>

#include "common/rng.hpp"
#include "simulation/raycast.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::simulation {
namespace {

/// Stop and go: each true pose drawn around its recorded one (Alhashimi et al. 2021 eq. 8).
std::vector<TruthStop> planRigStops(const RigSimConfig& c, std::uint64_t seed) {
  if (c.use_driving) {
    Scene scene;
    scene.path = c.driving;
    scene.path.kind = PathKind::driving;
    return planStops(scene, seed);
  }
  auto rng = makeRng(seed, 0);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<TruthStop> out;
  for (std::size_t k = 0; k < c.stops.size(); ++k) {
    TruthStop t;
    t.commanded = c.stops[k];
    t.actual = c.stops[k];
    t.actual.x_m += c.sigma_s_m * normal(rng);
    t.actual.y_m += c.sigma_s_m * normal(rng);
    t.actual.yaw_rad += c.sigma_psi_rad * normal(rng);
    t.first_scan = k * static_cast<std::size_t>(c.scans_per_stop);
    t.scans = static_cast<std::size_t>(c.scans_per_stop);
    out.push_back(t);
  }
  return out;
}

/// Distance along `ray` to the first pole it meets, and which (none: nullopt).
std::optional<std::pair<double, std::size_t>> firstPole(const std::vector<Cylinder>& poles,
                                                        const Ray& ray) {
  std::optional<std::pair<double, std::size_t>> best;
  for (std::size_t i = 0; i < poles.size(); ++i)
    if (const auto t = intersectCircle(ray, poles[i]); t && (!best || *t < best->first))
      best = std::make_pair(*t, i);
  return best;
}

/// Where and when a sensor sweeps: the vehicle's true pose, the stop and the scan's index.
struct SweepAt {
  const Pose2& vehicle;
  std::size_t stop, scan;
};

/// The sightings of one sensor in one scan: every beam of its grid that meets pole p first.
void sweep(const RigSimConfig& c, std::size_t s, const SweepAt& at, std::mt19937_64& rng,
           std::vector<RigSighting>& out) {
  const Pose2& vehicle = at.vehicle;
  const std::size_t stop = at.stop, scan = at.scan;
  const RigSimSensor& sensor = c.sensors[s];
  const Pose2 pose = compose(vehicle, sensor.mounting.pose());
  const double flip = sensor.mounting.flip();
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t p = 0; p < c.poles.size(); ++p) {
    const Cylinder& pole = c.poles[p];
    const double dx = pole.x_m - pose.x_m, dy = pole.y_m - pose.y_m;
    const double centre = std::hypot(dx, dy);
    if (centre <= pole.radius_m) continue;
    const double half = std::asin(pole.radius_m / centre);
    // the pole's bearing in the sensor frame
    const double mid = flip * wrapAngle(std::atan2(dy, dx) - pose.yaw_rad);
    const double inc = sensor.angle_increment_rad;
    const long first =
        std::max(0L, static_cast<long>(std::ceil((mid - half - sensor.angle_min_rad) / inc)));
    const long last =
        std::min(static_cast<long>(sensor.beams) - 1,
                 static_cast<long>(std::floor((mid + half - sensor.angle_min_rad) / inc)));
    RigSighting sighting{s, stop, scan, static_cast<int>(p) + 1, {}};
    for (long j = first; j <= last; ++j) {
      const double a = sensor.angle_min_rad + static_cast<double>(j) * inc;
      const double w = pose.yaw_rad + flip * a;
      const Ray ray{pose.x_m, pose.y_m, std::cos(w), std::sin(w)};
      const double e = normal(rng);  // drawn for every beam of the pole, so streams stay aligned
      const auto hit = c.occlusion ? firstPole(c.poles, ray) : std::nullopt;
      const auto own = intersectCircle(ray, pole);
      if (!own || (hit && hit->second != p)) continue;
      const double y = rangeReading(sensor.model, *own, e);
      if (y < sensor.model.range_min_m || y > sensor.model.range_max_m) continue;
      sighting.beams.push_back(BeamReading{a, y, static_cast<std::uint32_t>(j)});
    }
    if (!sighting.beams.empty()) out.push_back(std::move(sighting));
  }
}

}  // namespace

RigSimSample simulateRig(const RigSimConfig& c, std::uint64_t seed) {
  if (c.sensors.empty()) throw std::invalid_argument("simulateRig: no sensor");
  RigSimSample out;
  out.stops = planRigStops(c, seed);
  RigObservations& obs = out.obs;
  for (const RigSimSensor& s : c.sensors) {
    RigSensor r;
    r.name = s.name;
    r.prior = s.design;
    r.prior.upside_down = s.mounting.upside_down;
    r.prior_known = true;
    r.range_min_m = s.model.range_min_m;
    r.range_max_m = s.model.range_max_m;
    obs.sensors.push_back(r);
  }
  obs.vehicle_known = c.vehicle_known;
  if (c.publish_radius && !c.poles.empty()) obs.pole_radius_m = c.poles.front().radius_m;
  for (std::size_t k = 0; k < out.stops.size(); ++k) {
    const TruthStop& t = out.stops[k];
    obs.vehicle.push_back(t.commanded);  // a prior when known, else where the fit starts
    for (std::size_t i = 0; i < t.scans; ++i) {
      const std::size_t scan = t.first_scan + i;
      for (std::size_t s = 0; s < c.sensors.size(); ++s) {
        auto rng = makeRng(seed, 1 + scan * c.sensors.size() + s);
        // A rig scan index unique over sensors: the pooling groups by (sensor, stop, pole, beam).
        sweep(c, s, SweepAt{t.actual, k, scan * c.sensors.size() + s}, rng, obs.sightings);
      }
    }
  }
  return out;
}

}  // namespace lidarcal::simulation
