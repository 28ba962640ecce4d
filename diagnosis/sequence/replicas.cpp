// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/replicas.hpp"

#include <cmath>
#include <map>
#include <random>

#include "common/pose2.hpp"
#include "common/rng.hpp"
#include "common/stats_util.hpp"
#include "diagnosis/sequence/starts.hpp"

namespace lidarcal::diagnosis::sequence {
namespace {

/// Beam grid of the data: the step between neighbouring beams, and its origin.
void setBeamGrid(const LandmarkObservations& obs, simulation::LandmarkLevelConfig& c) {
  std::vector<double> steps, origins;
  for (const auto& s : obs.sightings)
    for (std::size_t j = 1; j < s.beams.size(); ++j) {
      const auto db =
          static_cast<double>(s.beams[j].beam) - static_cast<double>(s.beams[j - 1].beam);
      if (db >= 1.0 && db <= 3.0)
        steps.push_back(wrapAngle(s.beams[j].angle_rad - s.beams[j - 1].angle_rad) / db);
    }
  if (!steps.empty()) c.angle_increment_rad = upperMedian(steps);
  for (const auto& s : obs.sightings)
    for (const auto& b : s.beams)
      origins.push_back(
          wrapAngle(b.angle_rad - static_cast<double>(b.beam) * c.angle_increment_rad));
  if (!origins.empty()) c.angle_min_rad = upperMedian(origins);
}

/// The poses of a replica: each independently around its commanded pose (stop and go), or, under
/// the motion prior, as a drive's odometry is made: the replica's path drives the recorded steps
/// scaled by 1 + s, and its odometry (returned; the recorded one otherwise) reports each of them
/// over 1 + s with the prior's noise, chained from the first pose, so that the replicas drift as
/// the model says odometry does (noise on the path's side instead reads as a step scale).
std::vector<Pose2> drawPoses(const LandmarkObservations& obs, const PoseNoise& noise,
                             std::mt19937_64& rng, std::vector<TruthStop>& stops) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const Pose2& c0 = obs.commanded.front();
  std::vector<Pose2> reported = obs.commanded;
  for (std::size_t k = 0; k < stops.size(); ++k) {
    const Pose2& c = obs.commanded[k];
    Pose2& a = stops[k].actual;
    if (noise.motion && k > 0) {
      const Pose2 step = stepBetween(obs.commanded[k - 1], c);  // in the frame of the stop before
      const double len = motionStepLength(obs.commanded, k);
      const double st = noise.step_fraction * len + noise.step_floor_m;
      const double sh = noise.heading_per_m * len + noise.heading_floor_rad;
      a = compose(stops[k - 1].actual, Pose2{(1.0 + noise.scale) * step.x_m,
                                             (1.0 + noise.scale) * step.y_m, step.yaw_rad});
      Pose2 odometry;
      odometry.x_m = step.x_m + st * normal(rng);
      odometry.y_m = step.y_m + st * normal(rng);
      odometry.yaw_rad = step.yaw_rad + sh * normal(rng);
      reported[k] = compose(reported[k - 1], odometry);
      continue;
    }
    a.x_m = c0.x_m + (1.0 + noise.scale) * (c.x_m - c0.x_m) + noise.sigma_s_m * normal(rng);
    a.y_m = c0.y_m + (1.0 + noise.scale) * (c.y_m - c0.y_m) + noise.sigma_s_m * normal(rng);
    a.yaw_rad = wrapAngle(c.yaw_rad + noise.sigma_psi_rad * normal(rng));
  }
  return reported;
}

}  // namespace

ReplicaPlan replicaPlan(const LandmarkObservations& obs, const JointResult& fit,
                        bool radius_known) {
  ReplicaPlan plan;
  auto& c = plan.config;
  // Each landmark returns the median intensity of its readings (0: none recorded).
  std::map<int, std::vector<double>> intensities;
  for (const auto& s : obs.sightings)
    for (const auto& b : s.beams)
      if (b.hasIntensity()) intensities[s.landmark].push_back(b.intensity);
  for (const auto& [id, centre] : fit.centres) {
    Cylinder cyl{centre.x(), centre.y(), fit.radius_m};
    auto o = fit.effects.landmark_offset_m.find(id);
    if (o != fit.effects.landmark_offset_m.end()) cyl.range_offset_m = o->second;
    auto in = intensities.find(id);
    if (in != intensities.end()) cyl.intensity = median(in->second);
    c.landmarks.push_back(cyl);
    plan.ids.push_back(id);
  }
  std::map<std::size_t, std::pair<std::size_t, std::size_t>> scans;  // stop -> (first, last)
  for (const auto& s : obs.sightings) {
    plan.present.insert({s.scan, s.landmark});
    auto it = scans.find(s.stop);
    if (it == scans.end())
      scans[s.stop] = {s.scan, s.scan};
    else
      it->second = {std::min(it->second.first, s.scan), std::max(it->second.second, s.scan)};
  }
  for (std::size_t k = 0; k < obs.commanded.size(); ++k) {
    TruthStop t;
    t.commanded = obs.commanded[k];
    t.actual = fit.poses[k];
    auto it = scans.find(k);
    if (it != scans.end()) {
      t.first_scan = it->second.first;
      t.scans = it->second.second - it->second.first + 1;
    }
    c.stops.push_back(t);
  }
  c.model = fit.model;
  c.model.range_min_m = obs.range_min_m;
  c.model.range_max_m = obs.range_max_m;
  c.sigma_theta_rad = fit.sigma_theta_rad;
  c.beams = true;
  c.publish_radius = radius_known;
  c.effects.incidence_noise_exponent = fit.effects.incidence_noise_exponent;
  c.effects.incidence_bias_m = fit.effects.incidence_bias_m;
  c.effects.range_drift_m_per_scan = fit.effects.drift_m_per_scan;
  c.effects.range_drift_reference_scan = fit.effects.drift_reference_scan;
  c.effects.mixed_pixel_fraction = fit.effects.mixed_pixel_fraction;
  c.effects.noise_student_dof = fit.effects.student_dof;
  c.effects.range_resolution_m = fit.effects.range_grid_m;
  c.effects.dark_noise_exponent = fit.effects.dark_noise_exponent;
  if (fit.effects.dark_reference_intensity > 0.0)
    c.effects.dark_reference_intensity = fit.effects.dark_reference_intensity;
  c.mount_yaw_rad = fit.effects.angle_offset_rad;
  if (c.effects.mixed_pixel_fraction > 0.0) {
    // The fitted mixed pixels read uniformly up to the window's end: a background that far.
    const auto [cx, cy] = pathCentroid(obs.commanded);
    const double r = fit.window_max_m;
    c.walls = {Segment{cx - r, cy - r, cx + r, cy - r}, Segment{cx + r, cy - r, cx + r, cy + r},
               Segment{cx + r, cy + r, cx - r, cy + r}, Segment{cx - r, cy + r, cx - r, cy - r}};
  }
  setBeamGrid(obs, c);
  return plan;
}

PoseNoise poseNoise(const JointResult& fit, const JointConfig& cfg) {
  PoseNoise n;
  n.sigma_s_m = cfg.sigma_s_m;
  n.sigma_psi_rad = cfg.effects.estimate_heading ? fit.effects.heading_rms_rad : 0.0;
  n.scale = fit.effects.odometry_scale;
  n.motion = fit.motion_prior;
  n.step_fraction = cfg.motion_sigma_fraction;
  n.step_floor_m = cfg.motion_sigma_floor_m;
  n.heading_per_m = cfg.motion_heading_sigma_rad_per_m;
  n.heading_floor_rad = cfg.motion_heading_floor_rad;
  return n;
}

LandmarkObservations simulateReplica(ReplicaPlan plan, const LandmarkObservations& obs,
                                     const PoseNoise& noise, std::uint64_t seed,
                                     std::vector<std::vector<double>>* truth) {
  // The stop poses are redrawn: the baseline says how they scatter about the commanded ones,
  // and whatever the fitted poses show beyond that is evidence against it.
  auto rng = makeRng(seed, 0x9053ULL);
  std::vector<Pose2> odometry = drawPoses(obs, noise, rng, plan.config.stops);
  auto sample = simulation::simulateLandmarkLevel(plan.config, seed);
  LandmarkObservations out;
  out.commanded = std::move(odometry);
  out.landmark_radius_m = obs.landmark_radius_m;
  out.range_min_m = obs.range_min_m;
  out.range_max_m = obs.range_max_m;
  for (std::size_t i = 0; i < sample.obs.sightings.size(); ++i) {
    Sighting s = sample.obs.sightings[i];
    s.landmark = plan.ids.at(static_cast<std::size_t>(s.landmark - 1));
    if (!plan.present.count({s.scan, s.landmark})) continue;
    out.sightings.push_back(std::move(s));
    if (truth) truth->push_back(sample.true_range_m[i]);
  }
  return out;
}

}  // namespace lidarcal::diagnosis::sequence
