// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/model_comparison.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>
#include <boost/math/distributions/chi_squared.hpp>

namespace lidarcal::calibration {

bool insideFittedRange(const CalibrationModel& m, double d) {
  if (m.fitted_range_m) return d >= m.fitted_range_m->first && d <= m.fitted_range_m->second;
  return d >= m.model.range_min_m && d <= m.model.range_max_m;
}

Eigen::MatrixXd biasCovariance(const CalibrationModel& m, const std::vector<double>& distances_m) {
  const std::size_t p = m.model.bias.alpha.size();
  if (p == 0 || m.alpha_covariance.size() != p * p) return {};
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
      sigma(m.alpha_covariance.data(), static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p));
  if (!sigma.allFinite()) return {};
  Eigen::MatrixXd J(static_cast<Eigen::Index>(distances_m.size()), static_cast<Eigen::Index>(p));
  for (std::size_t i = 0; i < distances_m.size(); ++i)
    for (std::size_t j = 0; j < p; ++j)
      J(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = std::pow(distances_m[i], j);
  return J * sigma * J.transpose();
}

WaldTest waldTest(const Eigen::VectorXd& D, const Eigen::MatrixXd& C) {
  WaldTest t;
  if (D.size() == 0 || C.rows() != D.size() || !C.allFinite() || !D.allFinite()) return t;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(C);
  const double largest = eig.eigenvalues().maxCoeff();
  for (Eigen::Index i = 0; i < eig.eigenvalues().size(); ++i) {
    const double lambda = eig.eigenvalues()(i);
    if (!(lambda > 1e-10 * largest)) continue;
    const double u = eig.eigenvectors().col(i).dot(D);
    t.statistic += u * u / lambda;
    ++t.dof;
  }
  if (t.dof > 0)
    t.p = boost::math::cdf(boost::math::complement(boost::math::chi_squared(t.dof), t.statistic));
  return t;
}

ModelDifference compareModels(const CalibrationModel& a, const CalibrationModel& b,
                              const std::vector<double>& distances_m) {
  ModelDifference r;
  std::vector<double> shared;
  for (double d : distances_m)
    if (insideFittedRange(a, d) && insideFittedRange(b, d)) shared.push_back(d);
  const Eigen::MatrixXd c_a = biasCovariance(a, shared), c_b = biasCovariance(b, shared);
  if (shared.empty())
    r.why_not = "no distance lies inside both calibrations' fitted ranges";
  else if (c_a.size() == 0 || c_b.size() == 0)
    r.why_not = "a calibration without alpha_covariance (standard errors)";
  if (!r.why_not.empty()) return r;
  Eigen::VectorXd D(static_cast<Eigen::Index>(shared.size()));
  const Eigen::MatrixXd C = c_a + c_b;
  for (std::size_t i = 0; i < shared.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    D(k) = a.model.bias(shared[i]) - b.model.bias(shared[i]);
    r.difference_m.push_back(D(k));
    r.se_m.push_back(std::sqrt(std::max(0.0, C(k, k))));
  }
  r.wald = waldTest(D, C);
  if (r.wald.dof == 0) {
    r.why_not = "the calibrations' covariances are zero";
    return r;
  }
  r.tested = true;
  r.distances_m = shared;
  return r;
}

}  // namespace lidarcal::calibration
