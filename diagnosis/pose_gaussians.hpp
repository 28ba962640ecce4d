// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Gaussian algebra of a sequence's held-out predictions: the marginal covariances of a chain of
// poses from its block-tridiagonal information, its log-determinant, the leave-one-out density of
// a linear Gaussian block, and the distance along a beam to a pole when the pose is uncertain.

#include <vector>

#include <Eigen/Core>

namespace lidarcal::diagnosis {

/// Diagonal blocks of the inverse of a symmetric positive-definite block-tridiagonal matrix:
/// 3x3 blocks diagonal[k] on the diagonal and upper[k] at (k, k + 1) (upper may be longer; its
/// last block is not used). A forward pass of Schur complements and a backward pass, as in a
/// Kalman smoother: O(n) for n blocks instead of the dense inverse's O(n^3). The marginal
/// covariances of a chain of poses from its information matrix. `upper_out`, when given, gets
/// the inverse's blocks at (k, k + 1) too: the covariance of neighbouring poses.
std::vector<Eigen::Matrix3d> blockTridiagonalInverseDiagonal(
    const std::vector<Eigen::Matrix3d>& diagonal, const std::vector<Eigen::Matrix3d>& upper,
    std::vector<Eigen::Matrix3d>* upper_out = nullptr);

/// ln det of the same symmetric positive-definite block-tridiagonal matrix: the sum of ln det of
/// the forward pass's Schur complements. NaN when one is not positive definite.
double blockTridiagonalLogDet(const std::vector<Eigen::Matrix3d>& diagonal,
                              const std::vector<Eigen::Matrix3d>& upper);

/// Mean and variance of the distance along a beam to a circular pole of radius r, which is
/// along - sqrt(r^2 - perp^2) (`along`: to the ray's closest approach to the centre, `perp`: the
/// ray's miss distance), when (along, perp) are jointly normal about the given values with
/// covariance v and the beam is known to have hit the pole (|perp| < r). Away from the tangent
/// (6 standard deviations of perp inside it) the first-order variance and the root's curvature
/// serve; otherwise the root is averaged over perp's truncated normal (64 midpoints in t, with
/// perp = r sin t), along following perp by regression.
/// A miss distance past the tangent with no spread: mean `along`, variance 0.
/// root_extra = c > 0: the moments of along - sqrt(r^2 - perp^2) - c r cos(phi) instead, cos(phi) =
/// sqrt(r^2 - perp^2) / r clamped (clampCosIncidence): a reading with an incidence bias b reads
/// f(d) + b (1 - cos phi), which moves with perp as the distance does scaled by 1 + b / (r f'(d)),
/// so c = b / (r f'(d)). On a thin pole (r 2.75 cm, b 3.3 cm) that more than doubles the spread
/// a held-out reading has from its scan's pose (docs/results/hidden-effects.md).
struct DistanceMoments {
  double mean = 0.0, var = 0.0;
};
DistanceMoments poleDistanceMoments(double along, double perp, const Eigen::Matrix2d& v, double r,
                                    double root_extra = 0.0);

/// Leave-one-out log-density of one block of a (locally) linear Gaussian model, from the fit on
/// every block: r the block's residual at that fit and S = J C J^T its leverage (J its rows,
/// C the parameters' covariance), both in units of the block's own standard deviations. Left
/// out, the residual is (I - S)^-1 r with covariance (I - S)^-1, so
///   ln p = -r^T (I - S)^-1 r / 2 + ln det(I - S) / 2 - (dim / 2) ln(2 pi)
/// (in those units). NaN when I - S is not positive definite (nothing else determines the
/// block's parameters).
double leaveOneOutLogDensity(const Eigen::Vector3d& r, const Eigen::Matrix3d& s);

}  // namespace lidarcal::diagnosis
