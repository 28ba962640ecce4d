// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The discrepancy statistics of a sequence (diagnosis/battery.hpp lists them): score statistics
// of the residuals against range, incidence, position on the pole, landmark, stop, heading, time
// and bearing; the refined path against the commanded one; tails and the reading grid.
// Internal to the diagnosis library.

#include <map>
#include <string>
#include <vector>

#include "diagnosis/sequence/refits.hpp"

namespace lidarcal::diagnosis::sequence {

constexpr double kClip = 3.0;  // Huber clipping of standardised residuals in the score statistics

/// Per-reading quantities the statistics need, under a fit.
struct ReadingRow {
  JointReading r;       ///< the reading under the fit
  double z = 0.0;       ///< standardised residual
  double psi = 0.0;     ///< z clipped at kClip (Huber)
  double dmu_da = 0.0;  ///< derivative of its mean by the beam angle, metres per radian
};

/// Every reading of `obs` under `fit` with its standardised residual, clipped residual and the
/// derivative of its mean by the beam angle.
std::vector<ReadingRow> readingRows(const LandmarkObservations& obs, const JointResult& fit,
                                    const JointConfig& cfg);

/// Statistic name -> value.
using Statistics = std::map<std::string, double>;

/// Every statistic of the battery (and the candidates' scores) under a baseline fit.
Statistics sequenceStatistics(const LandmarkObservations& obs, const JointResult& fit,
                              const std::vector<ReadingRow>& rs, const JointConfig& cfg);

}  // namespace lidarcal::diagnosis::sequence
