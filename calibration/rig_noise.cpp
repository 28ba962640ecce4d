// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/rig_noise.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lidarcal::calibration::rig {
namespace {

constexpr double kLog2Pi = 1.8378770664093453;
constexpr double kSigmaFloor = 1e-5;  // metres: readings on a grid can repeat exactly

/// Degrees of freedom within the beams: the sum of n - 1.
double withinDof(const std::vector<NoiseSample>& samples) {
  double w = 0.0;
  for (const auto& s : samples) w += std::max(0.0, s.n - 1.0);
  return w;
}

/// Residual degrees of freedom of the means: their count less the fitted parameters' share.
double meanDof(const std::vector<NoiseSample>& samples) {
  double lev = 0.0;
  for (const auto& s : samples) lev += std::clamp(s.leverage, 0.0, 1.0);
  return std::max(1.0, static_cast<double>(samples.size()) - lev);
}

/// tau^2 >= 0 with sum r^2 / (v_i + tau^2) = dof (0 when the residuals are no larger than the
/// scatter within explains): the left side falls with tau^2, so bisection on a bracket.
double fitTauSquared(const std::vector<NoiseSample>& samples, const SensorNoise& noise,
                     double dof) {
  SensorNoise n0 = noise;
  n0.tau_m = 0.0;
  const auto chi2 = [&](double t2) {
    double c = 0.0;
    for (const auto& s : samples) c += s.residual * s.residual / (meanVariance(n0, s) + t2);
    return c;
  };
  if (chi2(0.0) <= dof) return 0.0;
  double lo = 0.0, hi = 1e-6;
  while (chi2(hi) > dof && hi < 1e4) hi *= 4.0;
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (chi2(mid) > dof ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// sigma_e of `kind` from the scatter within the beams, and that scatter's log-likelihood.
double withinFit(const std::vector<NoiseSample>& samples, NoiseKind kind, double* loglik) {
  double sum = 0.0, w = 0.0, logh = 0.0;
  for (const auto& s : samples) {
    if (s.n < 2.0) continue;
    const double h = noiseShape(kind, s.h);
    sum += s.within_ss / (h * h);
    w += s.n - 1.0;
    logh += (s.n - 1.0) * std::log(h * h);
  }
  const double var = std::max(sum / w, kSigmaFloor * kSigmaFloor);
  *loglik = -0.5 * (w * (kLog2Pi + std::log(var)) + logh + sum / var);
  return std::sqrt(var);
}

/// sigma_e of `kind` from the means' residuals (tau 0), and their log-likelihood.
double residualFit(const std::vector<NoiseSample>& samples, NoiseKind kind, double dof,
                   double* loglik) {
  double sum = 0.0, logv = 0.0;
  for (const auto& s : samples) {
    const double h = noiseShape(kind, s.h);
    sum += s.n * s.residual * s.residual / (h * h);
    logv += std::log(h * h / s.n);
  }
  const double var = std::max(sum / dof, kSigmaFloor * kSigmaFloor);
  const double n = static_cast<double>(samples.size());
  *loglik = -0.5 * (n * (kLog2Pi + std::log(var)) + logv + sum / var);
  return std::sqrt(var);
}

}  // namespace

double noiseShape(NoiseKind kind, double f) {
  return kind == NoiseKind::squared ? std::max(f * f, 1e-6) : 1.0;
}

double meanVariance(const SensorNoise& noise, const NoiseSample& s) {
  const double sd = noise.law.sigma_e * noiseShape(noise.law.kind, s.h);
  return sd * sd / s.n + noise.tau_m * noise.tau_m;
}

SensorNoise fitSensorNoise(const std::vector<NoiseSample>& samples,
                           const std::vector<NoiseKind>& kinds) {
  SensorNoise best;
  if (samples.empty() || kinds.empty()) return best;
  const double w = withinDof(samples);
  const double dof = meanDof(samples);
  const bool repeats = w >= std::max(10.0, static_cast<double>(samples.size()));
  double best_ll = -std::numeric_limits<double>::infinity();
  for (const NoiseKind kind : kinds) {
    double ll = 0.0;
    SensorNoise n;
    n.law.kind = kind;
    n.law.sigma_e = repeats ? withinFit(samples, kind, &ll) : residualFit(samples, kind, dof, &ll);
    n.from_repeats = repeats;
    if (ll > best_ll) {
      best_ll = ll;
      best = n;
    }
  }
  if (repeats) best.tau_m = std::sqrt(fitTauSquared(samples, best, dof));
  return best;
}

double pooledLogLikelihood(const std::vector<NoiseSample>& samples, const SensorNoise& noise) {
  double ll = 0.0;
  for (const auto& s : samples) {
    const double v = meanVariance(noise, s);
    ll -= 0.5 * (kLog2Pi + std::log(v) + s.residual * s.residual / v);
    if (s.n >= 2.0) {
      const double sd = std::max(noise.law.sigma_e * noiseShape(noise.law.kind, s.h), kSigmaFloor);
      ll -= 0.5 * ((s.n - 1.0) * (kLog2Pi + 2.0 * std::log(sd)) + s.within_ss / (sd * sd));
    }
  }
  return ll;
}

}  // namespace lidarcal::calibration::rig
