// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Statistics of the diagnosis (diagnosis/diagnosis.hpp): p-values calibrated on bootstrap
// replicas, held-out gains and likelihood ratios, their combination, multiple testing, score
// statistics and distances between distributions.

#include <vector>

#include "common/multiple_testing.hpp"  // holmAdjust, used beside these tests

#include "common/stats_util.hpp"

namespace lidarcal::diagnosis {

/// p-value of a measured statistic against the values it took on B bootstrap replicas of the
/// fitted baseline. The replicas' mean m and standard deviation s give a Student-t predictive
/// distribution with B - 1 degrees of freedom, t = (value - m) / (s sqrt(1 + 1/B)), so that
/// p-values far below 1/B (needed after a multiple-testing correction) are available from a few
/// dozen replicas. Statistics are built to be close to normal under the baseline (signed scores,
/// cube roots of chi-square sums). `effect_size` receives (value - m) / s.
double replicaPValue(double value, const std::vector<double>& replicas, bool two_sided,
                     double* effect_size = nullptr);

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

}  // namespace lidarcal::diagnosis
