// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Student's t distribution: its distribution function and quantiles, for intervals whose scale
// is estimated from few units (the predictive intervals of calibration/discrepancy.hpp use the
// degrees of freedom of the discrepancy's estimate). The distribution function comes from the
// regularised incomplete beta function, I_x(a, b), evaluated by its continued fraction
// (Abramowitz & Stegun 1964, 26.5.8, and 26.7.1 for the t distribution).

namespace lidarcal {

/// I_x(a, b) for a, b > 0 and x in [0, 1]; NaN outside.
double regularisedIncompleteBeta(double a, double b, double x);

/// P(T <= t) for T ~ Student t with `dof` > 0 degrees of freedom (dof = +inf: the standard
/// normal). NaN for dof <= 0 or NaN input.
double studentTCdf(double t, double dof);

/// The p-quantile of Student's t with `dof` > 0 degrees of freedom, p in (0, 1) (dof = +inf:
/// the standard normal's); NaN otherwise.
double studentTQuantile(double p, double dof);

/// Half-width factor of the central interval of probability `level` in (0, 1): the
/// (1 + level) / 2 quantile of Student's t with `dof` degrees of freedom (+inf: normal).
double centralTFactor(double level, double dof);

}  // namespace lidarcal
