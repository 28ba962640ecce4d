// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/closed_form.hpp"
#include "common/number_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include <Eigen/Dense>

namespace lidarcal::odometry {
namespace {

using Matrix5 = Eigen::Matrix<double, 5, 5>;
using Vector5 = Eigen::Matrix<double, 5, 1>;

Status refuse(StatusCode code, std::string message) { return {code, std::move(message)}; }

/// Step 1: theta_sm = J21 phi_L T + J22 phi_R T by linear least squares.
struct RotationFit {
  Status status;
  double j21 = 0.0, j22 = 0.0, spread = 0.0;
};

RotationFit fitRotation(const std::vector<OdometrySample>& samples,
                        const std::vector<std::size_t>& indices, const OdometrySettings& settings) {
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  Eigen::Vector2d moment = Eigen::Vector2d::Zero();
  for (const std::size_t i : indices) {
    const OdometrySample& s = samples[i];
    const Eigen::Vector2d wheels(s.left_wheel_rad_s * s.duration_s,
                                 s.right_wheel_rad_s * s.duration_s);
    scatter += wheels * wheels.transpose();
    moment += wheels * s.scan_match_theta_rad;
  }
  RotationFit fit;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(scatter);
  const double largest = eigen.eigenvalues()[1];
  fit.spread = largest > 0.0 ? eigen.eigenvalues()[0] / largest : 0.0;
  if (!(fit.spread >= settings.min_wheel_spread)) {
    fit.status = refuse(StatusCode::degenerate_motion,
                        "the wheels turned in one proportion only (spread of the wheel turns " +
                            significant(fit.spread, 3) + ", at least " +
                            significant(settings.min_wheel_spread, 3) +
                            " needed): the two wheel radii cannot be told apart");
    return fit;
  }
  const Eigen::Vector2d j = scatter.ldlt().solve(moment);
  fit.j21 = j[0];
  fit.j22 = j[1];
  return fit;
}

/// Step 2's normal matrix M = sum L'L over the samples.
Matrix5 loopNormalMatrix(const std::vector<OdometrySample>& samples,
                         const std::vector<std::size_t>& indices, double j21, double j22) {
  Matrix5 normal = Matrix5::Zero();
  for (const std::size_t i : indices) {
    const OdometrySample& s = samples[i];
    const double left = s.left_wheel_rad_s * s.duration_s,
                 right = s.right_wheel_rad_s * s.duration_s;
    const double turn = j21 * left + j22 * right;                       // o
    const double distance_per_axle = (j22 * right - j21 * left) / 2.0;  // v T / b
    double sin_over, cos_over;
    arcFactors(turn, sin_over, cos_over);
    const double c = std::cos(turn), sn = std::sin(turn);
    Eigen::Matrix<double, 2, 5> l;
    l << -distance_per_axle * sin_over, 1.0 - c, sn, s.scan_match_x_m, -s.scan_match_y_m,
        -distance_per_axle * cos_over, -sn, 1.0 - c, s.scan_match_y_m, s.scan_match_x_m;
    normal += l.transpose() * l;
  }
  return normal;
}

/// Step 2's constrained minimum: m = (b, l_x, l_y, cos, sin) with b > 0, and lambda.
struct LoopSolution {
  Status status;
  Vector5 m = Vector5::Zero();
  double lambda = 0.0;
};

LoopSolution solveLoop(const Matrix5& normal, const OdometrySettings& settings) {
  LoopSolution out;
  const Eigen::Matrix3d a = normal.topLeftCorner<3, 3>();
  const Eigen::Matrix<double, 3, 2> b = normal.topRightCorner<3, 2>();
  const Eigen::Vector3d diagonal = a.diagonal();
  double spread = 0.0;
  if (diagonal.minCoeff() > 0.0) {
    const Eigen::Vector3d scale = diagonal.cwiseSqrt().cwiseInverse();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scale.asDiagonal() * a *
                                                               scale.asDiagonal());
    spread = eigen.eigenvalues()[0] / eigen.eigenvalues()[2];
  }
  if (!(spread >= settings.min_translation_spread)) {
    out.status = refuse(StatusCode::degenerate_motion,
                        "the motion does not separate the axle from the laser's position "
                        "(spread " +
                            significant(spread, 3) + ", at least " +
                            significant(settings.min_translation_spread, 3) + " needed)");
    return out;
  }
  const Eigen::LDLT<Eigen::Matrix3d> a_solver(a);
  const Eigen::Matrix2d schur =
      normal.bottomRightCorner<2, 2>() - b.transpose() * a_solver.solve(b);
  // det(S - lambda I) = lambda^2 - tr(S) lambda + det(S): its roots, the smaller one stably.
  const double trace = schur.trace(), det = schur.determinant();
  const double gap = std::hypot(schur(0, 0) - schur(1, 1), 2.0 * schur(0, 1));  // larger - smaller
  const double larger = (trace + gap) / 2.0;
  if (!(larger > 0.0) || !(gap > 1e-12 * larger)) {
    out.status = refuse(StatusCode::degenerate_motion,
                        "the laser's heading is not determined by these samples (both roots of the "
                        "determinant condition coincide)");
    return out;
  }
  out.lambda = std::max(0.0, det / larger);  // the smallest non-negative root
  // The null vector of S - lambda I is perpendicular to its larger row.
  const Eigen::Matrix2d shifted = schur - out.lambda * Eigen::Matrix2d::Identity();
  const int row = shifted.row(0).squaredNorm() >= shifted.row(1).squaredNorm() ? 0 : 1;
  Eigen::Vector2d heading(-shifted(row, 1), shifted(row, 0));
  heading.normalize();
  Eigen::Vector3d rest = -a_solver.solve(b * heading);
  if (rest[0] < 0.0) {
    rest = -rest;
    heading = -heading;
  }
  out.m << rest, heading;
  if (!out.m.allFinite() || !(rest[0] > 0.0))
    out.status = refuse(StatusCode::degenerate_motion, "the axle came out as zero");
  return out;
}

}  // namespace

ClosedFormFit fitClosedForm(const std::vector<OdometrySample>& samples,
                            const std::vector<std::size_t>& indices,
                            const OdometrySettings& settings) {
  ClosedFormFit fit;
  if (indices.size() < static_cast<std::size_t>(settings.min_samples)) {
    fit.status =
        refuse(StatusCode::too_few_samples, std::to_string(indices.size()) + " samples, at least " +
                                                std::to_string(settings.min_samples) + " needed");
    return fit;
  }
  const RotationFit rotation = fitRotation(samples, indices, settings);
  fit.wheel_spread = rotation.spread;
  if (!rotation.status.ok()) {
    fit.status = rotation.status;
    return fit;
  }
  fit.j21 = rotation.j21;
  fit.j22 = rotation.j22;
  const LoopSolution loop =
      solveLoop(loopNormalMatrix(samples, indices, fit.j21, fit.j22), settings);
  if (!loop.status.ok()) {
    fit.status = loop.status;
    return fit;
  }
  fit.lambda_m2 = loop.lambda;
  const double axle = loop.m[0];
  fit.params = {-fit.j21 * axle, fit.j22 * axle, axle,
                loop.m[1],       loop.m[2],      std::atan2(loop.m[4], loop.m[3])};
  if (!(fit.params.left_radius_m > 0.0 && fit.params.right_radius_m > 0.0))
    fit.status =
        refuse(StatusCode::negative_axle,
               "positive wheel radii would need a negative axle (J21 = " + significant(fit.j21, 3) +
                   ", J22 = " + significant(fit.j22, 3) +
                   " rad per wheel rad, where a robot that turns left as its right wheel turns "
                   "forward has "
                   "J21 < 0 < J22)");
  return fit;
}

}  // namespace lidarcal::odometry
