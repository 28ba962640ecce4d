// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Identifiability of a sequence's candidate effects: the information on each effect that is left
// once the baseline's parameters (bias, radius, centres, stop poses with their priors) are free,
// from the linearised model. Internal to the diagnosis library.

#include <map>
#include <vector>

#include "diagnosis/sequence/statistics.hpp"

namespace lidarcal::diagnosis::sequence {

/// What the data can say about each effect once the baseline's parameters are free.
struct Identifiability {
  /// information kept after the nuisance parameters, trace(I_eff) / trace(I_raw)
  double ratio = 1.0;
  /// standard error of the effect's parameter(s) after them (RMS over components)
  double se = 0.0;
  double ref = 0.0;  ///< the smallest size worth naming (same unit); identifiable when se < ref
};

/// Mean-type effects: the model's Jacobian in the nuisance parameters and in the effect; I_eff is
/// the information on the effect left after profiling the nuisance out. Variance-type effects: the
/// spread of their covariate beyond a constant (the noise scale).
std::map<Effect, Identifiability> identifiability(const LandmarkObservations& obs,
                                                  const JointResult& fit,
                                                  const std::vector<ReadingRow>& rs,
                                                  const JointConfig& cfg);

}  // namespace lidarcal::diagnosis::sequence
