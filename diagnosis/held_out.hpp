// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Held-out log-likelihoods of the baseline and of each candidate, point by point, and the gain of
// a candidate over the baseline with its standard error over blocks (scans, stops, wall bins):
// the measure the diagnosis names a cause by.

#include <cstddef>
#include <vector>

#include "diagnosis/diagnosis.hpp"

namespace lidarcal::diagnosis {

const char* statisticOf(Effect e, DiagnoseMode mode);

/// Held-out log-likelihoods, point by point: of the baseline, of each candidate, and the block
/// (scan, stop or wall bin) each point belongs to; the standard error of a gain is over blocks.
struct HeldOut {
  std::vector<double> base;               ///< baseline, per held-out point, nats
  std::vector<std::vector<double>> cand;  ///< per candidate, aligned with `base`
  std::vector<std::size_t> block;         ///< block of each point
  double points = 0.0;                    ///< the count the gains are divided by ("per point")
  explicit HeldOut(std::size_t candidates) : cand(candidates) {}
  /// Mean baseline log-likelihood per point.
  double baselineMean() const;
};

/// Held-out gain of one candidate over the baseline.
struct HeldOutGain {
  double gain = 0.0;   ///< sum of the differences over `points`, nats per point
  double se = 0.0;     ///< its standard error from the per-block sums
  bool finite = true;  ///< every difference was finite
};
HeldOutGain heldOutGain(const HeldOut& held, std::size_t candidate);

/// Sets the candidate's held-out gain, its standard error and one-sided p-value.
void setHeldOutGain(CandidateResult& r, const HeldOutGain& g);

}  // namespace lidarcal::diagnosis
