// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/simulated_drive.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "common/pose2.hpp"
#include "common/rng.hpp"

namespace lidarcal::odometry {
namespace {

/// Wheel turns that drive `nominal` at forward speed v and turn rate w for `seconds`, one step
/// per scan period.
void command(const DriveSimulation& s, double v, double w, double seconds,
             std::vector<WheelStep>& steps) {
  const int n = static_cast<int>(std::lround(seconds / s.scan_period_s));
  const double dt = seconds / n;
  const OdometryParameters& m = s.nominal;
  for (int i = 0; i < n; ++i)
    steps.push_back({(v - w * m.axle_m / 2.0) * dt / m.left_radius_m,
                     (v + w * m.axle_m / 2.0) * dt / m.right_radius_m});
}

std::vector<WheelStep> commands(const DriveSimulation& s) {
  std::vector<WheelStep> steps;
  const double circle_s = 2.0 * kPi * s.circle_radius_m / s.speed_m_s;
  const double circle_w = s.speed_m_s / s.circle_radius_m;
  for (int lap = 0; lap < s.laps; ++lap) {
    for (int side = 0; side < 4; ++side) {
      command(s, s.speed_m_s, 0.0, s.side_m / s.speed_m_s, steps);
      command(s, 0.0, s.turn_rad_s, kPi / 2.0 / s.turn_rad_s, steps);
    }
    command(s, s.speed_m_s, circle_w, circle_s, steps);
    command(s, s.speed_m_s, -circle_w, circle_s, steps);
  }
  return steps;
}

/// The true poses: each step's true arc plus its odometry error.
std::vector<Eigen::Vector3d> truePoses(const DriveSimulation& s,
                                       const std::vector<WheelStep>& steps, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Eigen::Vector3d> poses{Eigen::Vector3d::Zero()};
  const OdometryParameters& t = s.truth.odometry;
  for (const WheelStep& step : steps) {
    const Eigen::Vector2d sigma = stepSigmas(step, s.nominal, s.noise);
    Eigen::Vector3d arc = robotDisplacement(t.left_radius_m, t.right_radius_m, t.axle_m,
                                            step.left_rad, step.right_rad);
    arc += Eigen::Vector3d(sigma[0] * normal(rng), sigma[0] * normal(rng), sigma[1] * normal(rng));
    poses.push_back(advance(poses.back(), arc));
  }
  return poses;
}

void sight(const DriveSimulation& s, const std::vector<Eigen::Vector3d>& poses,
           std::mt19937_64& rng, DriveRecord& record) {
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    for (std::size_t j = 0; j < s.poles.size(); ++j) {
      const Eigen::Vector2d seen = predictSighting(poses[k], s.poles[j], s.truth, s.pole_radius_m);
      const double surface = (seen[0] - s.truth.range_offset_m) / (1.0 + s.truth.range_scale);
      if (surface > s.max_range_m || surface <= 0.0) continue;
      if (std::abs(seen[1]) > s.field_of_view_rad / 2.0) continue;
      record.sightings.push_back(
          {k, static_cast<int>(j), seen[0] + s.noise.range_sigma_m * normal(rng),
           std::remainder(seen[1] + s.noise.bearing_sigma_rad * normal(rng), 2.0 * kPi)});
    }
  }
}

/// The beams of a sweep with one every `beam_step_rad` that hit each pole of each sighting.
void beams(const DriveSimulation& s, const std::vector<Eigen::Vector3d>& poses,
           std::mt19937_64& rng, DriveRecord& record) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const OdometryParameters& o = s.truth.odometry;
  for (const PoleSighting& seen : record.sightings) {
    const Eigen::Vector3d laser =
        advance(poses[seen.scan], {o.laser_x_m, o.laser_y_m, o.laser_theta_rad});
    const Eigen::Vector2d centre = s.poles[static_cast<std::size_t>(seen.pole)];
    const Eigen::Vector2d w = centre - laser.head<2>();
    const double bearing = std::remainder(std::atan2(w.y(), w.x()) - laser[2], 2.0 * kPi);
    const double half = std::asin(std::min(1.0, s.pole_radius_m / w.norm()));
    for (long m = std::lround(std::ceil((bearing - half) / s.beam_step_rad));
         m * s.beam_step_rad < bearing + half; ++m) {
      const double angle = std::remainder(m * s.beam_step_rad, 2.0 * kPi);
      const double reading = predictBeam(poses[seen.scan], centre, s.truth, s.pole_radius_m, angle);
      record.beams.push_back(
          {seen.scan, seen.pole, angle, reading + s.noise.range_sigma_m * normal(rng)});
    }
  }
}

}  // namespace

SimulatedDrive simulateDrive(const DriveSimulation& settings) {
  SimulatedDrive out;
  out.record.steps = commands(settings);
  out.record.pole_radius_m = settings.pole_radius_m;
  std::mt19937_64 motion = makeRng(settings.seed, 0);
  std::mt19937_64 sightings = makeRng(settings.seed, 1);
  out.truth.params = settings.truth;
  out.truth.poses = truePoses(settings, out.record.steps, motion);
  for (std::size_t j = 0; j < settings.poles.size(); ++j)
    out.truth.poles[static_cast<int>(j)] = settings.poles[j];
  sight(settings, out.truth.poses, sightings, out.record);
  if (settings.beam_step_rad > 0.0) {
    std::mt19937_64 beam_noise = makeRng(settings.seed, 2);
    beams(settings, out.truth.poses, beam_noise, out.record);
  }
  return out;
}

}  // namespace lidarcal::odometry
