// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A simulated drive among poles with a known truth, drawn from exactly the model of drive.hpp:
// the robot is commanded along a square with turns in place and two circles, one each way
// (wheel turns computed from the nominal parameters, driven with the true ones), every step's
// motion errs by the odometry noise, and every scan sees every pole within range. For tests and
// for the study of the joint fit against its Cramer-Rao bound.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "odometry/drive_fit.hpp"

namespace lidarcal::odometry {

struct DriveSimulation {
  /// what the robot's maker states, which the commands and the odometry's noise use
  OdometryParameters nominal{0.05, 0.05, 0.30, 0.10, 0.0, 0.0};
  /// the robot as it is: wheel radii 1 % off, a wider axle, a shifted and turned laser that
  /// reads 3 cm long
  DriveParameters truth{{0.0505, 0.0496, 0.303, 0.12, 0.02, 0.03}, 0.03, 0.0};
  std::vector<Eigen::Vector2d> poles = {{1.5, 1.5},  {4.5, -1.0},  {4.5, 4.0},
                                        {-1.5, 4.0}, {-2.0, -1.5}, {1.5, -2.5}};
  double pole_radius_m = 0.05;
  double max_range_m = 8.0;  ///< poles farther than this (to the surface) are not seen
  /// the laser's field of view, centred on its x axis (2 pi: all round)
  double field_of_view_rad = 2.0 * 3.14159265358979323846;
  double side_m = 3.0;      ///< the square's side
  double speed_m_s = 0.3;   ///< commanded forward speed
  double turn_rad_s = 0.8;  ///< commanded turn rate in place
  double circle_radius_m = 1.0;
  double scan_period_s = 0.1;  ///< time between scans
  int laps = 1;                ///< times the square and the circles are driven
  /// > 0: the record also holds the beams that hit each sighted pole (DriveRecord::beams), one
  /// every this many radians of the laser's sweep, each read with the range noise
  double beam_step_rad = 0.0;
  DriveNoise noise;
  std::uint64_t seed = 1;  ///< base seed (common/rng.hpp)
};

struct SimulatedDrive {
  DriveRecord record;
  DriveState truth;  ///< the true parameters, poses and poles
};

/// Draws one drive. Deterministic for a seed.
SimulatedDrive simulateDrive(const DriveSimulation& settings);

}  // namespace lidarcal::odometry
