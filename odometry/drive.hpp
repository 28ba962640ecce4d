// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A drive among poles as the joint calibration of odometry, mounting and range sees it: what
// the wheels turned between consecutive scans, and the poles each scan saw (range to the
// surface and bearing of the centre, in the laser's frame), with the eight calibrated
// quantities and their noise.
//
// The model. Robot pose x_k = (x, y, theta) at scan k, pose 0 the origin of the world frame.
//   odometry:  x_k^-1 (+) x_k+1 = d(r_L, r_R, b; wheel turns of step k) + e_k,
//              e_k ~ N(0, diag(s_t^2, s_t^2, s_r^2)),  s_t^2 = q_t^2 |distance| + f_t^2,
//              s_r^2 = q_r^2 |turn| + f_r^2, distance and turn from the nominal parameters;
//   sighting:  laser pose = x_k (+) l;  c the pole's centre in the laser frame;
//              range   = (|c| - R)(1 + a_1) + a_0 + N(0, s_range^2),
//              bearing = atan2(c_y, c_x) + N(0, s_bearing^2);
//   or, beam by beam (DriveRecord::beams), the range replaced by each beam that hit the pole:
//              reading = d (1 + a_1) + a_0 + N(0, s_range^2),
//              d the distance along the beam from the laser to the pole's circle,
// with d the arc of motion_model.hpp, l = (l_x, l_y, l_theta) the mounting, R the poles' known
// radius and (a_0, a_1) the range bias polynomial of Alhashimi et al. 2021 (eq. 3) to first
// order. Odometry errors are per metre driven and per radian turned, as a wheel's slip is.

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "odometry/motion_model.hpp"

namespace lidarcal::odometry {

/// How far each wheel turned between two consecutive scans, radians.
struct WheelStep {
  double left_rad = 0.0;
  double right_rad = 0.0;
};

/// One pole seen in one scan: the fitted circle's nearest range and its centre's bearing.
struct PoleSighting {
  std::size_t scan = 0;      ///< index of the scan (0 .. steps)
  int pole = 0;              ///< which pole, as associated across scans
  double range_m = 0.0;      ///< measured range to the pole's surface, metres
  double bearing_rad = 0.0;  ///< bearing of its centre in the laser frame, radians
};

/// One beam that hit a pole in one scan.
struct BeamReading {
  std::size_t scan = 0;    ///< index of the scan (0 .. steps)
  int pole = 0;            ///< which pole, as associated across scans
  double angle_rad = 0.0;  ///< the beam's direction in the laser frame, radians
  double range_m = 0.0;    ///< its reading, metres
};

struct DriveRecord {
  std::vector<WheelStep> steps;         ///< steps[k] moves the robot from scan k to k + 1
  std::vector<PoleSighting> sightings;  ///< in any order
  /// When not empty the fit explains these readings, beam by beam, in place of the sightings'
  /// ranges (of which only the bearings are kept): a circle fitted through returns that the
  /// range bias moved along their own beams is not where the pole is.
  std::vector<BeamReading> beams;
  double pole_radius_m = 0.0;  ///< the poles' radius, known (measured), metres
  std::size_t scans() const { return steps.size() + 1; }
  bool byBeam() const { return !beams.empty(); }
};

inline constexpr int kDriveParameterCount = 8;
using Vector8 = Eigen::Matrix<double, kDriveParameterCount, 1>;
using Matrix8 = Eigen::Matrix<double, kDriveParameterCount, kDriveParameterCount>;

/// The calibrated quantities, in the order of every vector here: (r_L, r_R, b, l_x, l_y,
/// l_theta, a_0, a_1).
struct DriveParameters {
  OdometryParameters odometry;
  double range_offset_m = 0.0;  ///< a_0: what the laser adds to every range, metres
  double range_scale = 0.0;     ///< a_1: relative range error (0.01: 1 % long)

  Vector8 toVector() const;
  static DriveParameters fromVector(const Vector8& v);
};

inline constexpr std::array<const char*, kDriveParameterCount> kDriveParameterNames = {
    "left_radius_m", "right_radius_m",  "axle_m",         "laser_x_m",
    "laser_y_m",     "laser_theta_rad", "range_offset_m", "range_scale"};

/// Which parameters the fit estimates (true) and which it holds at the value given.
using EstimatedSet = std::array<bool, kDriveParameterCount>;
/// Odometry, mounting and the range offset; the range scale held (with the wheel radii free a
/// range scale and a common scale of the wheels, axle, mounting and world cannot be told
/// apart).
inline constexpr EstimatedSet kEstimateAllButScale = {true, true, true, true,
                                                      true, true, true, false};

struct DriveNoise {
  double range_sigma_m = 0.01;          ///< s_range (of one beam, when fitted by beam)
  double bearing_sigma_rad = 0.005;     ///< s_bearing
  double slip_m_per_sqrt_m = 0.01;      ///< q_t: translation error per square root of metres driven
  double slip_rad_per_sqrt_rad = 0.02;  ///< q_r: heading error per square root of radians turned
  double floor_m = 1e-4;                ///< f_t
  double floor_rad = 1e-4;              ///< f_r
};

/// Pose `x` followed by the step `arc` (in x's frame); the heading is not wrapped, so that
/// headings along a drive stay continuous.
Eigen::Vector3d advance(const Eigen::Vector3d& x, const Eigen::Vector3d& arc);

/// What a noise-free laser reads of the pole centred at `pole` from robot pose `pose`: range to
/// the surface (through the range bias) and bearing of the centre, wrapped to [-pi, pi].
Eigen::Vector2d predictSighting(const Eigen::Vector3d& pose, const Eigen::Vector2d& pole,
                                const DriveParameters& params, double pole_radius_m);

/// The beams of `record` that pass within `fraction` of the pole's radius from the centre its
/// sighting in the same scan gives (range and bearing); the others, and beams without such a
/// sighting, are left out. Near the tangent a beam's distance to the circle changes faster than
/// any first-order fit follows (and real returns there mix the pole with what lies behind);
/// kCentralFraction keeps incidences below about 45 degrees.
DriveRecord centralBeams(const DriveRecord& record, double fraction);

/// The fraction `odometry-drive --beams` fits with, as `calibrate --reference` selects beams.
inline constexpr double kCentralFraction = 0.7;

/// What a noise-free laser reads along the beam at `angle_rad` (laser frame) from robot pose
/// `pose`, of the pole centred at `pole`: the distance to its circle through the range bias.
double predictBeam(const Eigen::Vector3d& pose, const Eigen::Vector2d& pole,
                   const DriveParameters& params, double pole_radius_m, double angle_rad);

/// Standard deviations (x and y, metres; heading, radians) of step `step`'s odometry error,
/// with distance and turn from `nominal`'s wheel radii and axle.
Eigen::Vector2d stepSigmas(const WheelStep& step, const OdometryParameters& nominal,
                           const DriveNoise& noise);

}  // namespace lidarcal::odometry
