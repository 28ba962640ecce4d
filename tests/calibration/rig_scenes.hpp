// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Simulated vehicles with two or three lidars, shared by the rig calibration's tests and the
// coverage bench (bench/rig_coverage.cpp): a forklift-like rig (front corner upright, back corner
// upside down), an optional third lidar on the side, poles around the vehicle.

#include <cmath>

#include "simulation/rig_sim.hpp"

namespace lidarcal::test {

/// A time-of-flight-like sensor: a small offset and scale error, constant noise.
inline RangeModel tofModel(double alpha0, double alpha1, double sigma_m) {
  RangeModel m;
  m.bias.alpha = {alpha0, alpha1};
  m.noise = NoiseModel{NoiseKind::constant, {}, sigma_m, 2.0};
  m.range_min_m = 0.05;
  m.range_max_m = 30.0;
  return m;
}

/// The rig: front lidar at the front-left corner (upright), back lidar at the back-right corner
/// (upside down), and with `three` a side lidar on the right; designs off by a few cm and degrees.
inline std::vector<simulation::RigSimSensor> rigSensors(bool three) {
  std::vector<simulation::RigSimSensor> s(three ? 3 : 2);
  s[0].name = "front";
  s[0].mounting = Mounting{1.50, 0.35, deg2rad(42.0), false, 0.07};
  s[0].design = Mounting{1.53, 0.33, deg2rad(40.0), false, 0.07};
  s[0].model = tofModel(0.012, 1.004, 0.004);
  s[1].name = "back";
  s[1].mounting = Mounting{-0.20, -0.45, deg2rad(-135.0), true, 0.07};
  s[1].design = Mounting{-0.23, -0.47, deg2rad(-132.0), true, 0.07};
  s[1].model = tofModel(-0.008, 0.997, 0.005);
  if (three) {
    s[2].name = "side";
    s[2].mounting = Mounting{0.65, -0.50, deg2rad(-90.0), false, 0.5};
    s[2].design = Mounting{0.62, -0.52, deg2rad(-92.0), false, 0.5};
    s[2].model = tofModel(0.005, 1.002, 0.006);
    s[2].model.noise = NoiseModel{NoiseKind::squared, {}, 0.002, 2.0};
  }
  return s;
}

/// Poles around the vehicle's working area (radius 45 mm, as the forklift's reflectors).
inline std::vector<Cylinder> rigPoles() {
  std::vector<Cylinder> p;
  const double xy[][2] = {{3.0, 1.2}, {2.6, -1.5}, {-1.5, -1.6}, {-1.8, 1.0},
                          {0.6, 2.2}, {0.8, -2.4}, {4.2, -0.2},  {-2.8, -0.3}};
  for (const auto& q : xy) p.push_back(Cylinder{q[0], q[1], 0.045});
  return p;
}

/// Stop and go through a turn: stops along a quarter circle and a straight piece.
inline simulation::RigSimConfig stopAndGo(bool three) {
  simulation::RigSimConfig c;
  c.sensors = rigSensors(three);
  c.poles = rigPoles();
  for (int k = 0; k < 8; ++k) {
    const double a = deg2rad(-40.0 + 12.0 * k);
    c.stops.push_back(Pose2{0.3 * k - 0.9, 0.15 * std::sin(a), a});
  }
  c.sigma_s_m = 0.01;
  c.sigma_psi_rad = deg2rad(0.3);
  c.scans_per_stop = 5;
  return c;
}

/// A vehicle that never stops: a loop with odometry noise, one sweep per sensor per pose.
inline simulation::RigSimConfig driving(bool three) {
  simulation::RigSimConfig c;
  c.sensors = rigSensors(three);
  c.poles = rigPoles();
  c.use_driving = true;
  c.driving.kind = PathKind::driving;
  c.driving.start = Pose2{-1.0, -0.3, 0.0};
  c.driving.stops = 120;
  c.driving.scans_per_stop = 1;
  c.driving.driving.speed_m_per_scan = 0.03;
  c.driving.driving.route = {RouteSegment{1.2, 0.0}, RouteSegment{1.0, deg2rad(90.0)},
                             RouteSegment{0.6, 0.0}};
  c.driving.driving.odometry = OdometryNoise{0.05, deg2rad(2.0), 0.02};
  c.scans_per_stop = 1;
  return c;
}

/// The static forklift: one stop, no recorded motion, poles on the right where both corners see
/// them.
inline simulation::RigSimConfig staticVehicle(bool three) {
  simulation::RigSimConfig c = stopAndGo(three);
  c.poles.clear();
  const double xy[][2] = {{2.6, -1.5}, {0.8, -2.4}, {2.0, -2.8},
                          {3.6, -0.9}, {1.4, -1.3}, {-0.4, -2.0}};
  for (const auto& q : xy) c.poles.push_back(Cylinder{q[0], q[1], 0.045});
  c.stops = {Pose2{0.0, 0.0, 0.0}};
  c.sigma_s_m = 0.0;
  c.sigma_psi_rad = 0.0;
  c.scans_per_stop = 20;
  return c;
}

}  // namespace lidarcal::test
