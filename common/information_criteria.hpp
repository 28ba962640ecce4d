// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The two information criteria the order choices compare: Akaike's (AIC) and Schwarz's (BIC),
// from a fit's minimised negative log-likelihood and its number k of free parameters.

#include <cmath>
#include <cstddef>

namespace lidarcal {

/// AIC = 2 k + 2 (-log L).
inline double akaike(double k, double neg_log_likelihood) {
  return 2.0 * k + 2.0 * neg_log_likelihood;
}

/// BIC = k log n + 2 (-log L), n the observations fitted.
inline double schwarz(double k, std::size_t n, double neg_log_likelihood) {
  return k * std::log(static_cast<double>(n)) + 2.0 * neg_log_likelihood;
}

}  // namespace lidarcal
