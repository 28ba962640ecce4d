// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The noise's shape terms of a sequence's candidates: which are estimated by restricted
// likelihood over the poses, that estimate, and which are shapes of the noise at all.
// Internal to the diagnosis library.

#include "diagnosis/sequence/refits.hpp"

namespace lidarcal::diagnosis::sequence {

/// The effects whose term is a factor of the noise that grows with a covariate of the reading by an
/// exponent: the incidence's gamma, (1 / cos phi)^gamma, and the darkness' delta,
/// (I_ref / I)^delta. Under the motion prior their exponent is estimated by restricted likelihood
/// (restrictedShapeEstimate); not the range law's kappa, whose maximum-likelihood estimate holds on
/// drives (docs/results/hidden-effects.md, Robots that never stop).
bool restrictedShape(Effect e);

/// The start `init` with effect e's exponent (restrictedShape) at `v`.
void setNoiseShape(Effect e, double v, JointInit& init);

/// Effect e's exponent (restrictedShape) on the readings of `obs` under `fit` (a fit of model
/// `cfg`, its geometry held) by restricted maximum likelihood over the poses: the Gaussian
/// log-likelihood of the residuals minus half the log-determinant of the poses' information
/// (poseChainInformation), maximised over the exponent and the noise's scale. A residual is
/// expected at sigma_i^2 (1 - h_i), h_i its leverage on its scan's pose; maximum likelihood with a
/// pose per scan reads the smaller residuals of the beams a pose rests on as less noise and drives
/// the incidence exponent of clean drives to its lower bound (docs/results/hidden-effects.md,
/// Robots that never stop). The scale found here is not kept. NaN with fewer than 10 readings
/// within 4 sigma. `statistic`, when given, gets the restricted likelihood ratio of the estimate
/// against the exponent at 0 (twice the log ratio, the scale profiled in both, the geometry held at
/// `fit`).
double restrictedShapeEstimate(const LandmarkObservations& obs, const JointResult& fit,
                               const JointConfig& cfg, Effect e, double* statistic = nullptr);

/// Effects of the noise's shape (kappa, gamma, delta, nu, the mixed-pixel fraction): their
/// parameters are estimated on the Gaussian residuals and only the law's scale by maximum
/// likelihood on the grid cells (by the t's EM under Student-t noise), so beside the rounded model
/// or the t their likelihood ratio is not chi-squared.
bool noiseShapeEffect(Effect e);

}  // namespace lidarcal::diagnosis::sequence
