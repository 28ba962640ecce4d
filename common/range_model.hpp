// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The range model shared by the simulator and the calibration.
//
//   Alhashimi et al. 2021 eq. 3:  r = sum_i alpha_i d^i + (sum_i beta_i d^i) e,   e ~ N(0, 1)
//   Alhashimi et al. 2016 eq. 1:  y = f(d) + f(d)^2 e,                            e ~ N(0,
//   sigma_e^2)
//
// d is the true distance (metres) from the sensor to the surface hit by the beam,
// r (or y) the reading. f is the bias polynomial, the noise multiplies a unit normal.

#include <string>
#include <vector>

namespace lidarcal {

/// alpha_0 + alpha_1 d + ... + alpha_{N-1} d^(N-1) by Horner's rule (Alhashimi et al. 2016 eq. 1's
/// f), for any scalar type (the Ceres residuals evaluate it on jets).
template <int N, typename T>
T evaluatePolynomial(const T* alpha, const T& d) {
  T f = alpha[N - 1];
  for (int i = N - 2; i >= 0; --i) f = f * d + alpha[i];
  return f;
}

/// Polynomial f(d) = sum_i alpha[i] d^i (Alhashimi et al. 2021 eq. 3, Alhashimi et al. 2016 eq. 3).
/// d and f in metres.
struct BiasPolynomial {
  /// Coefficients alpha_0..alpha_n (alpha_i in m^(1-i)). Default: identity f(d) = d.
  std::vector<double> alpha{0.0, 1.0};

  /// f(d), evaluated with Horner's rule.
  double operator()(double d_m) const;
  /// f'(d).
  double derivative(double d_m) const;
  /// Order n = alpha.size() - 1 (0 for an empty polynomial).
  int order() const { return alpha.empty() ? 0 : static_cast<int>(alpha.size()) - 1; }
};

/// How the standard deviation of the range noise depends on the true distance d.
enum class NoiseKind {
  none,        ///< noise-free readings
  constant,    ///< sigma(d) = sigma_e
  polynomial,  ///< sigma(d) = |sum_i beta_i d^i|            (Alhashimi et al. 2021 eq. 3)
  squared,     ///< sigma(d) = sigma_e f(d)^2                (Alhashimi et al. 2016 eq. 1)
  power,       ///< sigma(d) = sigma_e f(d)^exponent          (Alhashimi et al. 2016 H0..H3, eq. 10)
};

/// Range-noise model: the standard deviation of the reading around f(d).
struct NoiseModel {
  /// Which law the standard deviation follows. Default: Alhashimi et al. 2016's squared law.
  NoiseKind kind = NoiseKind::squared;
  /// Coefficients beta_0..beta_n of the polynomial law, metres. Used by `polynomial` only.
  std::vector<double> beta;
  /// Scale sigma_e (units: m for constant, m^-1 for squared, m^(1-exponent) for power).
  double sigma_e = 0.0;
  /// Exponent k of the power law sigma_e f(d)^k. Used by `power` only (k = 2 is `squared`).
  double exponent = 2.0;

  /// Standard deviation of the reading (metres) at true distance d for bias polynomial f.
  double stddev(double d_m, const BiasPolynomial& f) const;
};

/// Full range model of a sensor: bias, noise and the sensor's range window.
struct RangeModel {
  BiasPolynomial bias;       ///< f(d); identity by default
  NoiseModel noise;          ///< noise law around f(d)
  double range_min_m = 0.0;  ///< smallest reading the sensor reports, metres
  double range_max_m = 1e9;  ///< largest reading the sensor reports, metres
};

const char* toString(NoiseKind kind);
/// Parses a NoiseKind name; returns false when the name is unknown.
bool parseNoiseKind(const std::string& name, NoiseKind& kind);

}  // namespace lidarcal
