// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/motion_model.hpp"

#include <cmath>

namespace lidarcal::odometry {
namespace {

/// Derivatives of sin(a)/a and (1 - cos a)/a with respect to a (series near 0, as arcFactors).
void arcFactorDerivatives(double a, double& d_sin_over, double& d_cos_over) {
  const double a2 = a * a;
  if (std::abs(a) < kArcSeriesBelow) {
    d_sin_over = -a / 3.0 * (1.0 - a2 / 10.0 * (1.0 - a2 / 28.0 * (1.0 - a2 / 54.0)));
    d_cos_over = 0.5 * (1.0 - a2 / 4.0 * (1.0 - a2 / 18.0 * (1.0 - a2 / 40.0)));
    return;
  }
  const double half_sin = std::sin(a / 2.0);
  d_sin_over = (a * std::cos(a) - std::sin(a)) / a2;
  d_cos_over = (a * std::sin(a) - 2.0 * half_sin * half_sin) / a2;
}

}  // namespace

Vector6 OdometryParameters::toVector() const {
  Vector6 v;
  v << left_radius_m, right_radius_m, axle_m, laser_x_m, laser_y_m, laser_theta_rad;
  return v;
}

OdometryParameters OdometryParameters::fromVector(const Vector6& v) {
  return {v[0], v[1], v[2], v[3], v[4], v[5]};
}

Eigen::Vector3d predictedScanMatch(const OdometryParameters& params, const OdometrySample& sample) {
  const Vector6 v = params.toVector();
  return predictedScanMatch(v.data(), sample);
}

Eigen::Vector3d scanMatchResidual(const OdometryParameters& params, const OdometrySample& sample) {
  const Eigen::Vector3d measured(sample.scan_match_x_m, sample.scan_match_y_m,
                                 sample.scan_match_theta_rad);
  return measured - predictedScanMatch(params, sample);
}

Jacobian predictedScanMatchJacobian(const OdometryParameters& p, const OdometrySample& sample) {
  const double wheel_left = sample.left_wheel_rad_s * sample.duration_s;    // phi_L T
  const double wheel_right = sample.right_wheel_rad_s * sample.duration_s;  // phi_R T
  const double distance = (p.left_radius_m * wheel_left + p.right_radius_m * wheel_right) / 2.0;
  const double turn = (p.right_radius_m * wheel_right - p.left_radius_m * wheel_left) / p.axle_m;
  double f, g, df, dg;
  arcFactors(turn, f, g);
  arcFactorDerivatives(turn, df, dg);

  // d(distance)/d(r_L, r_R, b) and d(turn)/d(r_L, r_R, b)
  const Eigen::Vector3d d_distance(wheel_left / 2.0, wheel_right / 2.0, 0.0);
  const Eigen::Vector3d d_turn(-wheel_left / p.axle_m, wheel_right / p.axle_m, -turn / p.axle_m);

  const double cr = std::cos(turn), sr = std::sin(turn);
  const double cl = std::cos(p.laser_theta_rad), sl = std::sin(p.laser_theta_rad);
  Eigen::Matrix2d laser_rotation_t;  // R(l_theta)^T
  laser_rotation_t << cl, sl, -sl, cl;
  // d(R(turn) l_t)/d(turn)
  const Eigen::Vector2d d_rotated_mount(-sr * p.laser_x_m - cr * p.laser_y_m,
                                        cr * p.laser_x_m - sr * p.laser_y_m);

  Jacobian j = Jacobian::Zero();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d d_translation(d_distance[k] * f + distance * df * d_turn[k],
                                        d_distance[k] * g + distance * dg * d_turn[k]);
    j.block<2, 1>(0, k) = laser_rotation_t * (d_translation + d_rotated_mount * d_turn[k]);
    j(2, k) = d_turn[k];
  }
  Eigen::Matrix2d rotation_minus_identity;  // R(turn) - I
  rotation_minus_identity << cr - 1.0, -sr, sr, cr - 1.0;
  j.block<2, 2>(0, 3) = laser_rotation_t * rotation_minus_identity;
  // u = r_t + (R(turn) - I) l_t; d(R(l_theta)^T u)/d(l_theta)
  const Eigen::Vector2d u = Eigen::Vector2d(distance * f, distance * g) +
                            rotation_minus_identity * Eigen::Vector2d(p.laser_x_m, p.laser_y_m);
  j(0, 5) = -sl * u[0] + cl * u[1];
  j(1, 5) = -cl * u[0] - sl * u[1];
  return j;
}

}  // namespace lidarcal::odometry
