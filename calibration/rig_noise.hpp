// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to the rig calibration (rig_calibrate.hpp): each sensor's noise from its pooled beam
// readings. A beam seen n times on one pole at one stop gives its mean ybar and the sum of
// squared deviations S around it. With sigma(d) = sigma_e h(d) (h = 1 for the constant law,
// f(d)^2 for Alhashimi et al. 2016 eq. 1's squared law):
//   within a beam:  S / (sigma_e h)^2 ~ chi^2 with n - 1 degrees of freedom, whatever the geometry;
//   between beams:  ybar - f(d) ~ N(0, (sigma_e h)^2 / n + tau^2),
// tau the part of the error that repeats from scan to scan. sigma_e and the law come from the
// scatter within the beams when the scans repeat (enough degrees of freedom), tau from the
// residuals of the means, their degrees of freedom reduced by the leverage of the fitted
// parameters on them (the trace of the hat matrix: REML's correction, so that a fit with many
// poses per reading does not shrink the noise). Without repeated scans (a vehicle that never
// stops) tau is 0 and sigma_e comes from the residuals.

#include <vector>

#include "common/range_model.hpp"

namespace lidarcal::calibration::rig {

/// One pooled beam of one sensor at the current estimate.
struct NoiseSample {
  double h = 1.0;  ///< f(d) for the squared law's shape (the law picks h = f^2 or 1), metres
  double n = 1.0;  ///< readings pooled
  double within_ss = 0.0;  ///< sum of squared deviations of the readings around their mean, m^2
  double residual = 0.0;   ///< mean reading minus f(d), metres
  /// share of the fitted parameters in this residual (hat-matrix diagonal), 0..1
  double leverage = 0.0;
};

/// A sensor's noise: sigma(d) = sigma_e h(d), and tau.
struct SensorNoise {
  NoiseModel law;             ///< constant or squared, with sigma_e
  double tau_m = 0.0;         ///< std. dev. of the error a beam repeats from scan to scan, metres
  bool from_repeats = false;  ///< sigma_e came from the scatter within the beams
};

/// The shape h(d) of a law for a sample whose f(d) is `f`.
double noiseShape(NoiseKind kind, double f);

/// Variance of a pooled mean: (sigma_e h)^2 / n + tau^2.
double meanVariance(const SensorNoise& noise, const NoiseSample& s);

/// Fits sigma_e, the law (the most likely of `kinds`: constant, squared) and tau to the samples.
SensorNoise fitSensorNoise(const std::vector<NoiseSample>& samples,
                           const std::vector<NoiseKind>& kinds);

/// Log-likelihood of the samples' readings (the means and the scatter within), nats.
double pooledLogLikelihood(const std::vector<NoiseSample>& samples, const SensorNoise& noise);

}  // namespace lidarcal::calibration::rig
