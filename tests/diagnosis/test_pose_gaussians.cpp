// SPDX-License-Identifier: BSD-3-Clause
// Gaussian algebra of the held-out predictions (diagnosis/pose_gaussians.hpp) against dense and
// sampled oracles: the block-tridiagonal inverse and log-determinant, the leave-one-out density,
// and a beam's distance to a pole under pose uncertainty.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "calibration/joint_refinement.hpp"
#include "common/rng.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/pose_gaussians.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

TEST(DiagnoseStats, BlockTridiagonalInverseAndLogDetMatchTheDenseOnes) {
  // A chain of 9 poses: random information per pose (readings) plus random couplings between
  // neighbours (odometry steps), assembled as J^T J so that the matrix is positive definite.
  auto rng = makeRng(11, 3);
  std::normal_distribution<double> n01(0.0, 1.0);
  const int n = 9;
  std::vector<Eigen::Matrix3d> diag(n, Eigen::Matrix3d::Zero()), upper(n, Eigen::Matrix3d::Zero());
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  auto random3 = [&] {
    Eigen::Matrix3d m;
    for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = n01(rng);
    return m;
  };
  for (int k = 0; k < n; ++k) {
    const Eigen::Matrix3d j = random3();
    // some poses nearly unseen
    const Eigen::Matrix3d info = j.transpose() * j * (k % 3 == 1 ? 1e-3 : 1.0);
    diag[k] += info;
    dense.block<3, 3>(3 * k, 3 * k) += info;
  }
  for (int k = 0; k + 1 < n; ++k) {
    const Eigen::Matrix3d ja = random3(), jb = random3();
    diag[k] += ja.transpose() * ja;
    diag[k + 1] += jb.transpose() * jb;
    upper[k] += ja.transpose() * jb;
    dense.block<3, 3>(3 * k, 3 * k) += ja.transpose() * ja;
    dense.block<3, 3>(3 * k + 3, 3 * k + 3) += jb.transpose() * jb;
    dense.block<3, 3>(3 * k, 3 * k + 3) += ja.transpose() * jb;
    dense.block<3, 3>(3 * k + 3, 3 * k) += jb.transpose() * ja;
  }
  const Eigen::MatrixXd inverse = dense.inverse();
  std::vector<Eigen::Matrix3d> off;
  const auto blocks = diagnosis::blockTridiagonalInverseDiagonal(diag, upper, &off);
  ASSERT_EQ(blocks.size(), static_cast<std::size_t>(n));
  ASSERT_EQ(off.size(), static_cast<std::size_t>(n - 1));
  for (int k = 0; k < n; ++k) {
    const Eigen::Matrix3d want = inverse.block<3, 3>(3 * k, 3 * k);
    EXPECT_LT((blocks[k] - want).norm(), 1e-8 * want.norm()) << "block " << k;
    if (k + 1 == n) continue;
    const Eigen::Matrix3d want_off = inverse.block<3, 3>(3 * k, 3 * k + 3);
    EXPECT_LT((off[k] - want_off).norm(), 1e-8 * want.norm()) << "block " << k << ", " << k + 1;
  }
  EXPECT_TRUE(diagnosis::blockTridiagonalInverseDiagonal({}, {}).empty());
  EXPECT_THROW(diagnosis::blockTridiagonalInverseDiagonal(diag, {}), std::invalid_argument);
  // Its log-determinant (the restricted likelihood's term for the poses) from the same pass.
  const double log_det = std::log(dense.determinant());
  EXPECT_NEAR(diagnosis::blockTridiagonalLogDet(diag, upper), log_det, 1e-9 * std::abs(log_det));
  std::vector<Eigen::Matrix3d> indefinite = diag;
  indefinite[2] = -indefinite[2];
  EXPECT_TRUE(std::isnan(diagnosis::blockTridiagonalLogDet(indefinite, upper)));
}

TEST(DiagnoseStats, LeaveOneOutLogDensityMatchesTheRefitWithoutTheBlock) {
  // A linear Gaussian model in 6 parameters (two poses), observed in blocks of 3 rows with unit
  // noise: the formula from the fit on every block against the predictive density of the block
  // under the fit without it.
  auto rng = makeRng(17, 4);
  std::normal_distribution<double> n01(0.0, 1.0);
  const int blocks = 5;
  std::vector<Eigen::Matrix<double, 3, 6>> j(blocks);
  std::vector<Eigen::Vector3d> y(blocks);
  for (int b = 0; b < blocks; ++b) {
    // block 0: little leverage
    for (int i = 0; i < 18; ++i) j[b](i / 6, i % 6) = n01(rng) * (b == 0 ? 0.2 : 1.0);
    for (int i = 0; i < 3; ++i) y[b](i) = n01(rng) * 2.0;  // residuals of any size
  }
  auto fit = [&](int without, Eigen::Matrix<double, 6, 1>& theta,
                 Eigen::Matrix<double, 6, 6>& cov) {
    Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    for (int b = 0; b < blocks; ++b)
      if (b != without) {
        h += j[b].transpose() * j[b];
        g += j[b].transpose() * y[b];
      }
    cov = h.inverse();
    theta = cov * g;
  };
  Eigen::Matrix<double, 6, 1> theta;
  Eigen::Matrix<double, 6, 6> cov;
  fit(-1, theta, cov);
  for (int k = 0; k < blocks; ++k) {
    Eigen::Matrix<double, 6, 1> theta_k;
    Eigen::Matrix<double, 6, 6> cov_k;
    fit(k, theta_k, cov_k);
    const Eigen::Vector3d e = y[k] - j[k] * theta_k;
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() + j[k] * cov_k * j[k].transpose();
    const double want = -0.5 * e.dot(p.inverse() * e) - 0.5 * std::log(p.determinant()) -
                        1.5 * std::log(2.0 * std::acos(-1.0));
    const Eigen::Vector3d r = y[k] - j[k] * theta;
    const double got = diagnosis::leaveOneOutLogDensity(r, j[k] * cov * j[k].transpose());
    EXPECT_NEAR(got, want, 1e-9 * std::max(1.0, std::abs(want))) << "block " << k;
  }
  // A block that alone determines a direction of the parameters: S has an eigenvalue 1.
  EXPECT_TRUE(std::isnan(diagnosis::leaveOneOutLogDensity(Eigen::Vector3d(1.0, 0.0, 0.0),
                                                          Eigen::Matrix3d::Identity())));
}

namespace {
/// poleDistanceMoments(1.2, perp, v, r, extra) against the sampled moments of
/// along - q - extra r cos(phi) over the draws whose beam hits the pole (q = sqrt(r^2 - perp^2),
/// cos(phi) = q / r clamped as the model clamps it), for miss distances far inside the tangent,
/// near it, at it and past it (the fit's miss distance outside the pole while the reading came from
/// it).
void expectPoleMomentsMatchSamples(double r, double extra) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (const double perp : {0.0, 0.015, 0.024, 0.0275, 0.029, -0.031}) {
    for (const double sp : {0.0005, 0.002, 0.006}) {
      Eigen::Matrix2d v;
      v << 4e-6, 0.6 * 2e-3 * sp, 0.6 * 2e-3 * sp, sp * sp;
      const Eigen::Matrix2d l = v.llt().matrixL();
      double n = 0.0, m = 0.0, m2 = 0.0;
      for (int k = 0; k < 400000; ++k) {
        const Eigen::Vector2d x =
            Eigen::Vector2d(1.2, perp) + l * Eigen::Vector2d(n01(rng), n01(rng));
        if (std::abs(x(1)) >= r) continue;
        const double q = std::sqrt(r * r - x(1) * x(1));
        const double d = x(0) - q - extra * r * std::max(q / r, 0.05);
        n += 1.0;
        m += d;
        m2 += d * d;
      }
      if (n < 2000.0) continue;  // too few hits to check against
      m /= n;
      const double var = m2 / n - m * m;
      const auto got = diagnosis::poleDistanceMoments(1.2, perp, v, r, extra);
      const double se_mean = std::sqrt(var / n);
      EXPECT_NEAR(got.mean, m, 5.0 * se_mean + 2e-5)
          << "perp " << perp << " sd " << sp << " extra " << extra;
      EXPECT_NEAR(got.var, var, 0.05 * var)
          << "perp " << perp << " sd " << sp << " extra " << extra;
    }
  }
}
}  // namespace

TEST(DiagnoseStats, PoleDistanceMomentsMatchSampledHits) {
  // The distance along a beam to a pole of radius 2.75 cm when the ray's closest approach and
  // miss distance are uncertain (correlated normals).
  constexpr double r = 0.0275;
  expectPoleMomentsMatchSamples(r, 0.0);
  // No spread at all: the ray's own distance (its closest approach when it misses).
  EXPECT_DOUBLE_EQ(diagnosis::poleDistanceMoments(1.0, 0.03, Eigen::Matrix2d::Zero(), r).mean, 1.0);
  EXPECT_DOUBLE_EQ(diagnosis::poleDistanceMoments(1.0, 0.0, Eigen::Matrix2d::Zero(), r).mean,
                   1.0 - r);
}

TEST(DiagnoseStats, PoleReadingMomentsWithAnIncidenceBiasMatchSampledHits) {
  // A reading with an incidence bias b moves with the miss distance as along - (1 + b / r) q:
  // b 3.3 cm on r 2.75 cm, and a small b; the sampled moments the test computes itself.
  constexpr double r = 0.0275;
  expectPoleMomentsMatchSamples(r, 0.033 / r);
  expectPoleMomentsMatchSamples(r, 0.004 / r);
  // The extra root's variance: far inside the tangent, to first order (1 + c)^2 times the
  // distance's.
  Eigen::Matrix2d v;
  v << 0.0, 0.0, 0.0, 1e-8;
  const double plain = diagnosis::poleDistanceMoments(1.0, 0.01, v, r).var;
  EXPECT_NEAR(diagnosis::poleDistanceMoments(1.0, 0.01, v, r, 1.2).var, 2.2 * 2.2 * plain,
              1e-6 * plain);
  // With no spread: the root and its extra share at the given miss distance.
  const double q = std::sqrt(r * r - 0.01 * 0.01);
  EXPECT_NEAR(diagnosis::poleDistanceMoments(1.0, 0.01, Eigen::Matrix2d::Zero(), r, 1.2).mean,
              1.0 - q - 1.2 * q, 1e-12);
}

}  // namespace
}  // namespace lidarcal::diagnosis
