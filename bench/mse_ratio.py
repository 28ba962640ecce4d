# SPDX-License-Identifier: BSD-3-Clause
"""raw MSE / corrected MSE over paired entries with its 95 % interval, as `evaluate` computes it
(calibration/error_summary.hpp): exp(ln ratio +- t SE), SE by the delta method with the two mean
squares' covariance, t with entries - 1 degrees of freedom. For the benches, which pool the
entries of several E.json files."""
import math
from statistics import NormalDist


def t_quantile(p, dof):
    """Student-t quantile by its expansion in 1/dof about the normal's (Abramowitz & Stegun
    26.7.5); within 1e-3 of the exact value from 10 degrees of freedom, which the pooled folds
    here exceed."""
    z = NormalDist().inv_cdf(p)
    return (z + (z ** 3 + z) / (4 * dof) + (5 * z ** 5 + 16 * z ** 3 + 3 * z) / (96 * dof ** 2)
            + (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / (384 * dof ** 3))


def mse_ratio(raw, corrected):
    n = len(raw)
    r = [e * e for e in raw]
    c = [e * e for e in corrected]
    mr, mc = sum(r) / n, sum(c) / n
    cov = lambda a, ma, b, mb: sum((x - ma) * (y - mb) for x, y in zip(a, b)) / (n - 1) / n
    var = cov(r, mr, r, mr) / mr ** 2 + cov(c, mc, c, mc) / mc ** 2 - 2 * cov(r, mr, c, mc) / (mr * mc)
    half = t_quantile(0.975, n - 1) * math.sqrt(max(var, 0.0))
    return mr / mc, mr / mc * math.exp(-half), mr / mc * math.exp(half)


def text(raw, corrected):
    q, lo, hi = mse_ratio(raw, corrected)
    return f"{q:.2f} ({lo:.2f}-{hi:.2f})"
