// SPDX-License-Identifier: BSD-3-Clause
#include "simulation/observation_sim.hpp"

#include <cmath>
#include <random>

#include "common/rng.hpp"

namespace lidarcal::simulation {

std::vector<OdometryStep> commandedMotions(const ObservationScene& scene) {
  std::vector<OdometryStep> steps{OdometryStep{}};
  for (int lap = 0; lap < scene.repeat; ++lap)
    for (const auto& m : scene.motions)
      for (int i = 0; i < m.count; ++i)
        steps.push_back(OdometryStep{static_cast<int>(steps.size()), m.dx_m, m.dy_m, m.dtheta_rad});
  return steps;
}

Pose2 compose(const Pose2& pose, double dx_m, double dy_m, double dtheta_rad) {
  return lidarcal::compose(pose, Pose2{dx_m, dy_m, dtheta_rad});
}

ObservationSimulation simulateObservations(const ObservationScene& scene, std::uint64_t seed) {
  ObservationSimulation sim;
  sim.odometry = commandedMotions(scene);
  std::normal_distribution<double> normal(0.0, 1.0);

  auto process_rng = makeRng(seed, 0);
  const ProcessNoise& q = scene.process;
  sim.true_poses.reserve(sim.odometry.size());
  sim.true_poses.push_back(scene.start);
  for (std::size_t k = 1; k < sim.odometry.size(); ++k) {
    const auto& u = sim.odometry[k];
    const double wx = normal(process_rng), wy = normal(process_rng), wt = normal(process_rng);
    sim.true_poses.push_back(compose(sim.true_poses.back(), u.dx_m + std::sqrt(q.dx_var_m2) * wx,
                                     u.dy_m + std::sqrt(q.dy_var_m2) * wy,
                                     u.dtheta_rad + std::sqrt(q.dtheta_var_rad2) * wt));
  }

  std::vector<std::mt19937_64> sensor_rng;
  for (std::size_t s = 0; s < scene.sensors.size(); ++s) sensor_rng.push_back(makeRng(seed, 1 + s));
  for (std::size_t k = 0; k < sim.true_poses.size(); ++k) {
    const Pose2& pose = sim.true_poses[k];
    for (std::size_t s = 0; s < scene.sensors.size(); ++s) {
      const RangeBearingSensor& sensor = scene.sensors[s];
      for (std::size_t j = 0; j < scene.landmarks.size(); ++j) {
        const double e1 = normal(sensor_rng[s]), e2 = normal(sensor_rng[s]);
        double lx = 0.0, ly = 0.0;
        pose.toSensor(scene.landmarks[j].x_m, scene.landmarks[j].y_m, lx, ly);
        const double range = std::hypot(lx, ly), bearing = std::atan2(ly, lx);
        if (range < sensor.min_range_m || range > sensor.max_range_m) continue;
        if (std::abs(bearing) > 0.5 * sensor.fov_rad) continue;
        Observation o;
        o.stop = static_cast<int>(k);
        o.sensor = static_cast<int>(s);
        o.landmark = static_cast<int>(j);
        o.range_m = range + sensor.noise.range_mean_m + std::sqrt(sensor.noise.range_var_m2) * e1;
        o.bearing_rad = wrapAngle(bearing + sensor.noise.bearing_mean_rad +
                                  std::sqrt(sensor.noise.bearing_var_rad2) * e2);
        sim.observations.push_back(o);
      }
    }
  }
  return sim;
}

}  // namespace lidarcal::simulation
