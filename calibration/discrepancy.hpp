// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Model discrepancy of a range model fitted to measured distances (calibrate --reference): how
// far the sensor's mean reading at a distance the fit did not see may lie from the fitted
// polynomial, beyond the polynomial's own uncertainty. A real sensor is not a polynomial (the
// Hokuyo UST-30LX of docs/results/real-sensors.md leaves a structured +-10 mm against the tape);
// the coefficients' covariance says how well the polynomial is pinned down, not how far the
// sensor is from it.
//
// Following Kennedy & O'Hagan (2001), the sensor's mean reading is the polynomial plus a
// discrepancy delta(d), here a Gaussian term of variance tau^2 that is independent between
// the measured distances (the Hokuyo's residual changes sign between tape distances 20-40 mm
// apart, so no smoothness is assumed). Each measured entry g (one target at one stop, one tape
// measurement) gives the weighted mean residual r_g of its readings about the fit, at the mean
// distance d_g of its readings:
//   r_g = x(d_g)' beta + u_g + e_g,   u_g ~ N(0, tau^2),   e_g ~ N(0, k_g),
// with k_g known: the readings' noise averaged over the entry (pooled within-entry scatter over
// the entry's weight) plus the stated tape error carried through the slope, (f'(d_g) sigma_tape)^2.
// This is a random-effects meta-regression (each entry a "study" with known within-study
// variance): tau^2 is its restricted maximum likelihood (REML) estimate (Patterson & Thompson
// 1971; Viechtbauer 2005 for meta-analysis), which accounts for the polynomial's own degrees of
// freedom, and has entries - coefficients degrees of freedom. The predictive standard error of f
// at a new distance is sqrt(SE_curve(d)^2 + tau^2), its intervals Student-t quantiles with those
// degrees of freedom (as the prediction interval of a random-effects meta-analysis, Higgins,
// Thompson & Spiegelhalter 2009). An interval that also adds known variances (a tape error, the
// noise of a mean) takes more degrees of freedom by Welch-Satterthwaite.

#include <cstddef>
#include <map>
#include <vector>

#include "common/calibration_model.hpp"
#include "common/range_model.hpp"

namespace lidarcal::calibration {

/// One measured entry summarised about a fitted f.
struct EntryResidual {
  std::size_t entry = 0;    ///< the entry's label (REF.json distances index)
  double distance_m = 0.0;  ///< weighted mean true distance of its readings, metres
  double residual_m = 0.0;  ///< weighted mean of reading - f(distance) over its readings, metres
  /// k_g: noise of that mean plus (f'(d) sigma_tape)^2, square metres
  double known_variance_m2 = 0.0;
  double tape_sigma_m = 0.0;  ///< its stated tape error, metres
  double weight = 0.0;        ///< W_g: the sum of its readings' weights
  std::size_t readings = 0;   ///< readings it holds
};

/// The entries' residuals about f. d_m, y_m, weight (of the noise law, 1 / sigma_i^2 up to a
/// common factor), entry and tape_sigma_m are per reading and of one length; a reading with
/// weight 0 is left out. Entries in ascending label order.
std::vector<EntryResidual> entryResiduals(const std::vector<double>& d_m,
                                          const std::vector<double>& y_m,
                                          const std::vector<double>& weight,
                                          const std::vector<std::size_t>& entry,
                                          const std::vector<double>& tape_sigma_m,
                                          const BiasPolynomial& f);

/// The restricted log-likelihood of tau (metres) in the meta-regression above with a polynomial
/// mean of `order` (up to a constant).
double restrictedLogLikelihood(const std::vector<EntryResidual>& entries, int order, double tau_m);

/// tau by REML (method "reml"), dof = entries - (order + 1), tape_sigma_m the RMS of the
/// entries' stated tape errors. Method "none" (with a note saying why) when the entries cannot
/// leave a degree of freedom.
Discrepancy estimateDiscrepancy(const std::vector<EntryResidual>& entries, int order);

/// One entry judged by the others: what the random-effects fit of the other entries (tau by
/// REML over them, the polynomial by generalised least squares) predicts for it.
struct DeletedResidual {
  std::size_t entry = 0;    ///< the entry's label
  double distance_m = 0.0;  ///< its mean distance, metres
  double error_m = 0.0;     ///< its residual less the others' prediction, metres
  /// sqrt(tau_(-g)^2 + k_g + SE of the others' prediction^2), metres.
  double se_m = 0.0;
  int dof = 0;           ///< the others' degrees of freedom: entries - 1 - coefficients
  double p_value = 1.0;  ///< two-sided P(|T| >= |error / se|), T ~ Student t with dof
};

/// The studentized deleted residual of every entry (the case-deletion outlier diagnostic of a
/// meta-regression; Viechtbauer & Cheung 2010): entry g against the fit of the others, with the
/// discrepancy re-estimated without it, so that a blunder (a wrong stop number or tape reading)
/// does not hide by widening its own yardstick. Empty when the others would leave no degree of
/// freedom (fewer than order + 3 entries).
std::vector<DeletedResidual> deletedResiduals(const std::vector<EntryResidual>& entries, int order);

/// The weight of each entry's readings in the random-effects fit of the polynomial, relative
/// to the noise law's: 1 / (W_g (tau^2 + k_g)), so that entry g counts by 1 / (tau^2 + k_g) in
/// all, its readings sharing that by the noise law. This is the generalised least squares, and
/// with tau at its REML estimate the REML estimate, of the meta-regression's coefficients. Where
/// the discrepancy or a stated tape error outweighs an entry's noise, every entry counts about
/// alike: a hundred more readings at one distance do not say more about the sensor's departure
/// there. Keyed by entry label; empty when no discrepancy is estimated, or when tau and every
/// stated tape error are 0 (then the factors are all alike and the noise law's fit stands).
std::map<std::size_t, double> randomEffectsFactors(const std::vector<EntryResidual>& entries,
                                                   const Discrepancy& discrepancy);

/// sqrt(curve_se^2 + sigma^2) with the discrepancy's sigma (curve_se when none is estimated);
/// both in the same units. NaN when curve_se is.
double predictiveStandardError(double curve_se, const Discrepancy& discrepancy);

/// Half-width factor of the central predictive interval of probability `level`: the Student-t
/// quantile with the discrepancy's degrees of freedom (the normal's when none is estimated).
/// `known_share` in [0, 1) is the part of the interval's variance taken as exact rather than
/// estimated from the entries: a stated tape error, the noise of a mean of many readings. The
/// estimated part carries the discrepancy's dof, the known part infinitely many, and the whole
/// dof / (1 - known_share)^2 (Welch-Satterthwaite; Satterthwaite 1946, JCGM 100:2008 G.4).
double predictiveFactor(const Discrepancy& discrepancy, double level, double known_share = 0.0);

/// known / (estimated + known) of two variances (0 when both are 0): the known_share of an
/// interval whose variance is the estimated one plus a known one.
double knownShare(double estimated_variance, double known_variance);

}  // namespace lidarcal::calibration
