// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Parametric bootstrap replicas of a static recording: the same beams and scans simulated with
// the project's simulator from a fitted model, and the standardised residuals and per-bin
// variances of replicas refitted with the baseline. Internal to the diagnosis library.

#include <cstdint>
#include <vector>

#include "common/range_effects.hpp"
#include "diagnosis/static_scene/reading_model.hpp"
#include "diagnosis/static_scene/wall_model.hpp"

namespace lidarcal::diagnosis::static_scene {

/// The baseline's readings, simulated with the project's simulator (reading level): the same
/// beams and scans, true distance from the bin's location (wall bins: the wall model with a
/// roughness draw), the fitted range model, optionally with effects.
BinnedReadings simulateStatic(const BinnedReadings& d, const std::vector<BinFit>& f,
                              const WallFit& w, const ReadingModel& m, std::uint64_t seed,
                              const RangeEffects& fx);

/// Residual records of a data set under a fit (measured or simulated).
std::vector<ResidualRecord> residualRecordsOf(const BinnedReadings& dd,
                                              const std::vector<BinFit>& ff,
                                              const ReadingModel& mm);

/// Standardised residuals and per-bin variances of simulations refitted with the baseline.
struct SimSample {
  std::vector<double> z;                 ///< standardised residuals of every simulation
  std::vector<std::vector<double>> var;  ///< per bin, over the simulations
  void add(const std::vector<ResidualRecord>& rec, const std::vector<BinFit>& fr) {
    for (const auto& r : rec) z.push_back(r.z);
    for (std::size_t k = 0; k < fr.size(); ++k)
      if (fr[k].n > 0) var[k].push_back(fr[k].s2);
  }
};

}  // namespace lidarcal::diagnosis::static_scene
