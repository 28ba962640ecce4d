// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The motion model of a differential-drive robot carrying a 2D laser (Censi et al. 2013): the
// six parameters, the arc the robot drives in one sample, the laser displacement those imply
// and its Jacobian with respect to the parameters.
//
// With wheel speeds phi_L, phi_R constant over T the robot drives an arc with
//   v = (r_L phi_L + r_R phi_R) / 2,   omega = (r_R phi_R - r_L phi_L) / b,
// and moves by (v T sin(omega T) / (omega T), v T (1 - cos(omega T)) / (omega T), omega T) in
// its frame at the start of the interval. The laser, mounted at l = (l_x, l_y, l_theta) in the
// robot frame, sees the displacement  s = (-)l (+) r (+) l  in its own start frame (the loop
// "robot motion then mounting = mounting then laser motion").
//
// The templated functions take any scalar (double, Ceres jets) so that a later joint fit costs
// the same model; predictedScanMatchJacobian() is its analytic derivative.

#include <array>

#include <Eigen/Core>

#include "common/odometry_sample.hpp"

namespace lidarcal::odometry {

inline constexpr int kParameterCount = 6;
using Vector6 = Eigen::Matrix<double, kParameterCount, 1>;
using Matrix6 = Eigen::Matrix<double, kParameterCount, kParameterCount>;
using Jacobian = Eigen::Matrix<double, 3, kParameterCount>;

/// The calibrated quantities, in the order of every vector and covariance here:
/// (r_L, r_R, b, l_x, l_y, l_theta).
struct OdometryParameters {
  double left_radius_m = 0.0;    ///< r_L, radius of the left wheel, metres
  double right_radius_m = 0.0;   ///< r_R, radius of the right wheel, metres
  double axle_m = 0.0;           ///< b, distance between the wheels' contact points, metres
  double laser_x_m = 0.0;        ///< l_x, laser origin forward of the robot's, metres
  double laser_y_m = 0.0;        ///< l_y, laser origin left of the robot's, metres
  double laser_theta_rad = 0.0;  ///< l_theta, laser heading in the robot frame, radians

  Vector6 toVector() const;
  static OdometryParameters fromVector(const Vector6& v);
};

/// Names of the parameters in files and tables, in the order above.
inline constexpr std::array<const char*, kParameterCount> kParameterNames = {
    "left_radius_m", "right_radius_m", "axle_m", "laser_x_m", "laser_y_m", "laser_theta_rad"};

/// Below this |angle| (radians) the arc factors use their Taylor series (exact to double).
inline constexpr double kArcSeriesBelow = 1e-2;

/// sin(a) / a and (1 - cos a) / a, continuous (with their derivatives) through a = 0.
template <typename T>
void arcFactors(const T& a, T& sin_over_a, T& one_minus_cos_over_a) {
  using std::abs;
  using std::cos;
  using std::sin;
  if (abs(a) < T(kArcSeriesBelow)) {
    const T a2 = a * a;
    sin_over_a = T(1.0) - a2 / T(6.0) * (T(1.0) - a2 / T(20.0) * (T(1.0) - a2 / T(42.0)));
    one_minus_cos_over_a =
        a / T(2.0) * (T(1.0) - a2 / T(12.0) * (T(1.0) - a2 / T(30.0) * (T(1.0) - a2 / T(56.0))));
    return;
  }
  const T half_sin = sin(a / T(2.0));
  sin_over_a = sin(a) / a;
  one_minus_cos_over_a = T(2.0) * half_sin * half_sin / a;  // 1 - cos a without cancellation
}

/// The robot's displacement (x forward, y left, theta; robot frame at the start) when its left
/// and right wheels turn by `left_turn_rad` and `right_turn_rad`, for wheel radii and axle in
/// metres.
template <typename T>
Eigen::Matrix<T, 3, 1> robotDisplacement(const T& left_radius, const T& right_radius, const T& axle,
                                         double left_turn_rad, double right_turn_rad) {
  const T left = left_radius * T(left_turn_rad);     // r_L phi_L T
  const T right = right_radius * T(right_turn_rad);  // r_R phi_R T
  const T distance = (left + right) / T(2.0);        // v T
  const T turn = (right - left) / axle;              // omega T
  T sin_over, cos_over;
  arcFactors(turn, sin_over, cos_over);
  return {distance * sin_over, distance * cos_over, turn};
}

/// The robot's displacement over `sample` (robot frame at the interval's start).
template <typename T>
Eigen::Matrix<T, 3, 1> robotDisplacement(const T& left_radius, const T& right_radius, const T& axle,
                                         const OdometrySample& sample) {
  return robotDisplacement(left_radius, right_radius, axle,
                           sample.left_wheel_rad_s * sample.duration_s,
                           sample.right_wheel_rad_s * sample.duration_s);
}

/// The laser displacement the parameters predict for `sample`, (-)l (+) r (+) l, in the
/// laser's frame at the interval's start: x, y (metres), theta (radians). `params` holds the
/// six parameters in the order of OdometryParameters.
template <typename T>
Eigen::Matrix<T, 3, 1> predictedScanMatch(const T* params, const OdometrySample& sample) {
  using std::cos;
  using std::sin;
  const Eigen::Matrix<T, 3, 1> r = robotDisplacement(params[0], params[1], params[2], sample);
  const T cr = cos(r[2]), sr = sin(r[2]);
  const T cl = cos(params[5]), sl = sin(params[5]);
  // u = r_t + R(r_theta) l_t - l_t: where the laser ends up, minus where it started (robot frame)
  const T ux = r[0] + cr * params[3] - sr * params[4] - params[3];
  const T uy = r[1] + sr * params[3] + cr * params[4] - params[4];
  return {cl * ux + sl * uy, -sl * ux + cl * uy, r[2]};  // R(l_theta)^T u, and the turn
}

/// predictedScanMatch() for plain parameters.
Eigen::Vector3d predictedScanMatch(const OdometryParameters& params, const OdometrySample& sample);

/// Its derivative with respect to (r_L, r_R, b, l_x, l_y, l_theta), analytic: rows x, y, theta.
Jacobian predictedScanMatchJacobian(const OdometryParameters& params, const OdometrySample& sample);

/// What the laser measured minus what the parameters predict: x, y (m), theta (rad).
Eigen::Vector3d scanMatchResidual(const OdometryParameters& params, const OdometrySample& sample);

}  // namespace lidarcal::odometry
