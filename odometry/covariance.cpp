// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/covariance.hpp"

#include <Eigen/Dense>

namespace lidarcal::odometry {

Eigen::Vector3d residualVariances(const std::vector<OdometrySample>& samples,
                                  const std::vector<std::size_t>& indices,
                                  const OdometryParameters& params) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const std::size_t i : indices) sum += scanMatchResidual(params, samples[i]);
  const Eigen::Vector3d mean = sum / static_cast<double>(indices.size());
  Eigen::Vector3d squares = Eigen::Vector3d::Zero();
  for (const std::size_t i : indices) {
    const Eigen::Vector3d e = scanMatchResidual(params, samples[i]) - mean;
    squares += e.cwiseProduct(e);
  }
  return squares / static_cast<double>(indices.size());
}

FisherCovariance fisherCovariance(const std::vector<OdometrySample>& samples,
                                  const std::vector<std::size_t>& indices,
                                  const OdometryParameters& params,
                                  const Eigen::Vector3d& variances) {
  const Eigen::Vector3d weights = variances.cwiseMax(kVarianceFloor).cwiseInverse();
  Matrix6 information = Matrix6::Zero();
  for (const std::size_t i : indices) {
    const Jacobian j = predictedScanMatchJacobian(params, samples[i]);
    information += j.transpose() * weights.asDiagonal() * j;
  }
  FisherCovariance out;
  // Scaled to unit diagonal first: the parameters' units differ (metres, radians).
  const Vector6 diagonal = information.diagonal();
  if (!(diagonal.minCoeff() > 0.0) || !information.allFinite()) {
    out.status = {StatusCode::degenerate_motion,
                  "the samples carry no information on some parameter"};
    return out;
  }
  const Vector6 scale = diagonal.cwiseSqrt().cwiseInverse();
  const Matrix6 scaled = scale.asDiagonal() * information * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6> eigen(scaled);
  if (!(eigen.eigenvalues()[0] > 1e-12 * eigen.eigenvalues()[kParameterCount - 1])) {
    out.status = {StatusCode::degenerate_motion,
                  "the information matrix is singular: some combination of the parameters is "
                  "not determined by these samples"};
    return out;
  }
  const Matrix6 scaled_inverse = eigen.eigenvectors() *
                                 eigen.eigenvalues().cwiseInverse().asDiagonal() *
                                 eigen.eigenvectors().transpose();
  out.covariance = scale.asDiagonal() * scaled_inverse * scale.asDiagonal();
  return out;
}

}  // namespace lidarcal::odometry
