// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The closed-form estimate of Censi et al. 2013 from a set of samples, in two steps.
//
// 1. Rotation. The robot and the laser turn by the same angle, so for every sample
//      theta_sm = J21 phi_L T + J22 phi_R T,   J21 = -r_L / b,  J22 = r_R / b;
//    J21 and J22 follow by linear least squares.
// 2. The rest. With J21, J22 known the robot's translation in a sample is b times a known vector
//    c = (w sin(o)/o, w (1 - cos o)/o), w = (J22 phi_R - J21 phi_L) T / 2, o = (J21 phi_L +
//    J22 phi_R) T, and the loop "robot motion (+) mounting = mounting (+) laser motion" reads,
//    per sample, L m = 0 with m = (b, l_x, l_y, cos l_theta, sin l_theta) and
//      L = [ -c_x  1 - cos o    sin o      s_x  -s_y ]
//          [ -c_y  -sin o       1 - cos o  s_y   s_x ].
//    Minimise m' M m, M = sum L'L, subject to cos^2 + sin^2 = 1 (m' W m = 1, W = diag(0,0,0,1,1)):
//    (M - lambda W) m = 0 and the cost is lambda. det(M - lambda W) = det(A) det(S - lambda I)
//    with A the (b, l_x, l_y) block of M and S = D - B' A^-1 B its Schur complement, so the
//    determinant condition is the quadratic lambda^2 - tr(S) lambda + det(S) = 0: take its
//    smallest non-negative root, (cos, sin) the unit null vector of S - lambda I, (b, l_x, l_y)
//    = -A^-1 B (cos, sin), the sign that makes b > 0; then r_L = -J21 b, r_R = J22 b.
//
// Refusals (a status, never an exception): too few samples, wheel turns in one proportion only
// or no translation to separate the axle from the laser position (degenerate_motion), and
// positive wheel radii that would need a negative axle (negative_axle: a wheel's sign or side
// swapped in the data).

#include <cstddef>
#include <vector>

#include "common/odometry_sample.hpp"
#include "common/status.hpp"
#include "odometry/motion_model.hpp"
#include "odometry/settings.hpp"

namespace lidarcal::odometry {

struct ClosedFormFit {
  Status status;              ///< ok, too_few_samples, degenerate_motion or negative_axle
  OdometryParameters params;  ///< the estimate (meaningful when ok)
  double j21 = 0.0;           ///< rotation fit: -r_L / b, radians of turn per radian of wheel
  double j22 = 0.0;           ///< rotation fit: r_R / b, radians of turn per radian of wheel
  /// the Lagrange multiplier, which is the constrained fit's sum of squared loop residuals, m^2
  double lambda_m2 = 0.0;
  /// smaller / larger eigenvalue of the wheels' scatter matrix (the rotation fit's conditioning)
  double wheel_spread = 0.0;
  bool ok() const { return status.ok(); }
};

/// The closed form on the samples listed in `indices` (into `samples`).
ClosedFormFit fitClosedForm(const std::vector<OdometrySample>& samples,
                            const std::vector<std::size_t>& indices,
                            const OdometrySettings& settings);

}  // namespace lidarcal::odometry
