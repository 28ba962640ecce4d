// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/pose_gaussians.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>

#include "common/range_effects.hpp"

namespace lidarcal::diagnosis {

DistanceMoments poleDistanceMoments(double along, double perp, const Eigen::Matrix2d& v, double r,
                                    double root_extra) {
  // The root's extra share: root_extra r cos(phi), cos(phi) = q / r clamped as the model clamps it.
  const auto extra = [&](double q) {
    return root_extra == 0.0 ? 0.0 : root_extra * r * clampCosIncidence(q / r);
  };
  const double sp = std::sqrt(std::max(v(1, 1), 0.0));
  if (std::abs(perp) < r && r - std::abs(perp) > 6.0 * sp) {
    const double q = std::sqrt(r * r - perp * perp);
    const double k = q > 0.05 * r ? 1.0 + root_extra : 1.0;  // the clamped cosine is flat in perp
    const Eigen::Vector2d g(1.0, k * perp / q);  // d(along - q - extra) / d(along, perp)
    // the root's curvature in the mean
    return {along - q - extra(q) + 0.5 * k * v(1, 1) * r * r / (q * q * q), g.dot(v * g)};
  }
  if (!(sp > 0.0)) {
    const double q = std::sqrt(std::max(r * r - perp * perp, 0.0));
    return {along - q - extra(q), 0.0};
  }
  double lo = std::max(-r, perp - 8.0 * sp), hi = std::min(r, perp + 8.0 * sp);
  // far past the tangent: the normal's tail inside, falling at (|perp| - r) / sp^2
  if (!(lo < hi)) {
    const double width = std::min(2.0 * r, 10.0 * sp * sp / (std::abs(perp) - r));
    lo = perp > 0.0 ? r - width : -r;
    hi = perp > 0.0 ? r : -r + width;
  }
  const double beta = v(0, 1) / v(1, 1), along_var = std::max(v(0, 0) - beta * v(0, 1), 0.0);
  // perp = r sin(t): the root r cos(t) is smooth in t where it is steep in perp (the tangent).
  constexpr std::size_t kPoints = 64;
  const double t0 = std::asin(std::clamp(lo / r, -1.0, 1.0)),
               t1 = std::asin(std::clamp(hi / r, -1.0, 1.0));
  std::array<double, kPoints> logw{}, d{};
  for (std::size_t k = 0; k < kPoints; ++k) {
    const double t = t0 + (t1 - t0) * (static_cast<double>(k) + 0.5) / static_cast<double>(kPoints);
    const double x = r * std::sin(t), u = (x - perp) / sp, q = r * std::cos(t);
    logw[k] = -0.5 * u * u + std::log(std::cos(t));
    d[k] = along + beta * (x - perp) - q - extra(q);
  }
  const double top = *std::max_element(logw.begin(), logw.end());
  double sw = 0.0, m = 0.0, m2 = 0.0;
  for (std::size_t k = 0; k < kPoints; ++k) {
    const double w = std::exp(logw[k] - top);
    sw += w;
    m += w * d[k];
    m2 += w * d[k] * d[k];
  }
  m /= sw;
  return {m, std::max(m2 / sw - m * m, 0.0) + along_var};
}

double leaveOneOutLogDensity(const Eigen::Vector3d& r, const Eigen::Matrix3d& s) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(Eigen::Matrix3d::Identity() - s);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-9))
    return std::numeric_limits<double>::quiet_NaN();
  constexpr double kTwoPi = 6.283185307179586;
  return -0.5 * r.dot(ldlt.solve(r)) + 0.5 * ldlt.vectorD().array().log().sum() -
         1.5 * std::log(kTwoPi);
}

std::vector<Eigen::Matrix3d> blockTridiagonalInverseDiagonal(
    const std::vector<Eigen::Matrix3d>& diagonal, const std::vector<Eigen::Matrix3d>& upper,
    std::vector<Eigen::Matrix3d>* upper_out) {
  using Mat3 = Eigen::Matrix3d;
  const std::size_t n = diagonal.size();
  if (n == 0) return {};
  if (upper.size() + 1 < n)
    throw std::invalid_argument(
        "blockTridiagonalInverseDiagonal: one upper block per pair of neighbours");
  // D_0 = A_0, D_k+1 = A_k+1 - B_k^T D_k^-1 B_k;  C_n-1 = D_n-1^-1,
  // C_k = D_k^-1 + D_k^-1 B_k C_k+1 B_k^T D_k^-1, and C_k,k+1 = -D_k^-1 B_k C_k+1.
  std::vector<Mat3> dinv(n), cov(n);
  Mat3 d = diagonal[0];
  for (std::size_t k = 0; k < n; ++k) {
    dinv[k] = d.inverse();
    if (k + 1 < n) d = diagonal[k + 1] - upper[k].transpose() * dinv[k] * upper[k];
  }
  cov[n - 1] = dinv[n - 1];
  for (std::size_t k = n - 1; k-- > 0;)
    cov[k] = dinv[k] + dinv[k] * upper[k] * cov[k + 1] * upper[k].transpose() * dinv[k];
  if (upper_out) {
    upper_out->assign(n > 0 ? n - 1 : 0, Mat3::Zero());
    for (std::size_t k = 0; k + 1 < n; ++k) (*upper_out)[k] = -dinv[k] * upper[k] * cov[k + 1];
  }
  return cov;
}

double blockTridiagonalLogDet(const std::vector<Eigen::Matrix3d>& diagonal,
                              const std::vector<Eigen::Matrix3d>& upper) {
  const std::size_t n = diagonal.size();
  if (upper.size() + 1 < n && n > 0)
    throw std::invalid_argument("blockTridiagonalLogDet: one upper block per pair of neighbours");
  double sum = 0.0;
  Eigen::Matrix3d d = n > 0 ? diagonal[0] : Eigen::Matrix3d::Identity();
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::LLT<Eigen::Matrix3d> llt(d);
    if (llt.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
    sum += 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
    if (k + 1 < n) d = diagonal[k + 1] - upper[k].transpose() * llt.solve(upper[k]);
  }
  return sum;
}

}  // namespace lidarcal::diagnosis
