// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Outlier trimming (Censi et al. 2013): scan matching fails now and then (a featureless view, a
// person walking by) and its displacement is then wrong by decimetres. After a fit, the samples
// whose disagreement with it lies above a percentile in translation (the norm of the x, y
// residual) or in rotation (|theta residual|) are dropped, and the fit is repeated.

#include <cstddef>
#include <vector>

#include "common/odometry_sample.hpp"
#include "odometry/motion_model.hpp"

namespace lidarcal::odometry {

/// The value of `values` at `percentile` (percent, in (0, 100]) by nearest rank: the one at rank
/// ceil(percentile / 100 * n) when sorted ascending. `values` must not be empty.
double nearestRankPercentile(std::vector<double> values, double percentile);

/// One round: of the samples listed in `indices`, those whose translation and rotation residuals
/// under `params` both lie at or below the `percentile` of their kind over these samples, in the
/// order given.
std::vector<std::size_t> trimRound(const std::vector<OdometrySample>& samples,
                                   const std::vector<std::size_t>& indices,
                                   const OdometryParameters& params, double percentile);

}  // namespace lidarcal::odometry
