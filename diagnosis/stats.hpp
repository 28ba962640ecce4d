#pragma once
// Statistics of the diagnosis (diagnosis/diagnosis.hpp): p-values calibrated on bootstrap
// replicas, multiple testing, distances between distributions, and the rule that names a cause.

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/stats_util.hpp"
#include "diagnosis/diagnosis.hpp"

namespace lidarcal::diagnosis {

/// p-value of a measured statistic against the values it took on B bootstrap replicas of the
/// fitted baseline. The replicas' mean m and standard deviation s give a Student-t predictive
/// distribution with B - 1 degrees of freedom, t = (value - m) / (s sqrt(1 + 1/B)), so that
/// p-values far below 1/B (needed after a multiple-testing correction) are available from a few
/// dozen replicas. Statistics are built to be close to normal under the baseline (signed scores,
/// cube roots of chi-square sums). `effect_size` receives (value - m) / s.
double replicaPValue(double value, const std::vector<double>& replicas, bool two_sided, double* effect_size = nullptr);

/// Fills a Discrepancy from its measured value and its replica values.
Discrepancy makeDiscrepancy(std::string name, std::string variable, std::string description, double value,
                            const std::vector<double>& replicas, bool two_sided);

/// Diagonal blocks of the inverse of a symmetric positive-definite block-tridiagonal matrix:
/// 3x3 blocks diagonal[k] on the diagonal and upper[k] at (k, k + 1) (upper may be longer; its
/// last block is not used). A forward pass of Schur complements and a backward pass, as in a
/// Kalman smoother: O(n) for n blocks instead of the dense inverse's O(n^3). The marginal
/// covariances of a chain of poses from its information matrix. `upper_out`, when given, gets
/// the inverse's blocks at (k, k + 1) too: the covariance of neighbouring poses.
std::vector<Eigen::Matrix3d> blockTridiagonalInverseDiagonal(const std::vector<Eigen::Matrix3d>& diagonal,
                                                             const std::vector<Eigen::Matrix3d>& upper,
                                                             std::vector<Eigen::Matrix3d>* upper_out = nullptr);

/// ln det of the same symmetric positive-definite block-tridiagonal matrix: the sum of ln det of
/// the forward pass's Schur complements. NaN when one is not positive definite.
double blockTridiagonalLogDet(const std::vector<Eigen::Matrix3d>& diagonal, const std::vector<Eigen::Matrix3d>& upper);

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
DistanceMoments poleDistanceMoments(double along, double perp, const Eigen::Matrix2d& v, double r, double root_extra = 0.0);

/// Leave-one-out log-density of one block of a (locally) linear Gaussian model, from the fit on
/// every block: r the block's residual at that fit and S = J C J^T its leverage (J its rows,
/// C the parameters' covariance), both in units of the block's own standard deviations. Left
/// out, the residual is (I - S)^-1 r with covariance (I - S)^-1, so
///   ln p = -r^T (I - S)^-1 r / 2 + ln det(I - S) / 2 - (dim / 2) ln(2 pi)
/// (in those units). NaN when I - S is not positive definite (nothing else determines the
/// block's parameters).
double leaveOneOutLogDensity(const Eigen::Vector3d& r, const Eigen::Matrix3d& s);

/// One-sided p-value of a held-out gain with standard error se: P(N(0, 1) >= gain / se); 1 for
/// a gain that is not positive, NaN without a standard error.
double heldoutPValue(double gain, double se);

/// p-value of a candidate from its two tests (Bonferroni): the held-out gain and the
/// bootstrap-calibrated score statistic aimed at it, 2 min(p_heldout, p_score). The score test
/// is the more powerful where the evidence is in few observations (the odometry of a handful of
/// stops), the held-out test where the baseline's fit bent to absorb the effect. NaN entries
/// are left out.
double combinedPValue(double p_heldout, double p_score);
/// The same over three tests: 3 min(p_heldout, p_score, p_lr), NaN entries left out (and the
/// factor counting only the finite ones).
double combinedPValue(double p_heldout, double p_score, double p_lr);

/// p-value of a likelihood-ratio statistic 2 (nll_baseline - nll_extended) for an effect with one
/// parameter (chi-square, one degree of freedom); NaN for other parameter counts. A statistic
/// at or below 0 gives 1.
double likelihoodRatioPValue(double statistic, int parameters);

/// p-value of a likelihood-ratio statistic for one parameter whose null lies on the bound of its
/// range (a noise exponent that cannot fall below 0): under the null the estimate sits on the
/// bound half the time, so the statistic is 0 or chi-square with one degree of freedom, half and
/// half (Self and Liang 1987): half likelihoodRatioPValue's; 1 at or below 0.
double boundedLikelihoodRatioPValue(double statistic);

/// What a discrepancy statistic is, for the battery table.
struct StatisticInfo {
  const char* name;         ///< e.g. "spread_vs_incidence"
  const char* variable;     ///< what the residuals are compared against
  const char* description;  ///< how it is computed
  bool two_sided;           ///< both directions count
};

/// The battery: each listed statistic's measured value against its values on the replicas
/// (statistics missing from `measured` are left out).
std::vector<Discrepancy> makeBattery(const std::vector<StatisticInfo>& infos, const std::map<std::string, double>& measured,
                                     const std::map<std::string, std::vector<double>>& replicas);

/// Holm's step-down adjustment of p-values (NaN entries are left out and stay NaN).
std::vector<double> holmAdjust(const std::vector<double>& p);

/// Two-sample Kolmogorov-Smirnov distance sup |F_a - F_b| (0 when either is empty).
double ksDistance(std::vector<double> a, std::vector<double> b);

/// Cube root of a chi-square sum over its degrees of freedom (Wilson-Hilferty): close to normal.
double cubeRootChi2(double chi2, double dof);

/// Score statistic of a term in the mean: clipped standardised residuals psi against the
/// term's covariate over sigma (xs), over the square root of its information; ~N(0, 1) under
/// the model when the covariate is not absorbed by its parameters.
double meanScore(const std::vector<double>& psi, const std::vector<double>& xs);

/// Score statistic of a term in the log standard deviation: clipped squared residuals z^2 (at
/// 3) against the centred covariate g; ~N(0, 1) under the model.
double spreadScore(const std::vector<double>& z, const std::vector<double>& g);

/// Huber's psi: z clipped to [-c, c].
double huberPsi(double z, double c = 3.0);

/// E[min(Z^2, c^2)] and Var[min(Z^2, c^2)] for a standard normal Z.
double clippedSquareMean(double c = 3.0);
double clippedSquareVariance(double c = 3.0);

/// Names the cause from the candidates (fills `significant` and the Holm p-values first):
///   significant = Holm-adjusted p < alpha and held-out gain > 0;
///   none when none is; otherwise the largest held-out gain, replaced by a significant effect
///   nested in it (`nested`: pairs (simpler, richer), e.g. one zero-angle offset is the mean of
///   per-stop headings) whose gain is within two standard errors (parsimony);
///   not_identifiable when that effect is not identifiable, or when another significant effect is
///   within two standard errors of it and the pair is declared `indistinguishable`.
/// Returns the cause; `decision` receives the reason in words.
std::string nameCause(std::vector<CandidateResult>& candidates, double alpha, std::string& decision,
                      const std::vector<std::pair<Effect, Effect>>& nested = {},
                      const std::vector<std::pair<Effect, Effect>>& indistinguishable = {});

}  // namespace lidarcal::diagnosis
