// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The wall model: bin means on walls = alpha_0 + b (1 - cos phi) + p / cos(a - theta), with a
// roughness tau; Gauss-Newton, then leave-one-bin-out predictive log-likelihoods. With the walls
// as a geometric reference it measures the range offset alpha_0 (a constant along each beam
// bends a straight wall) and an incidence-dependent bias b. Internal to the diagnosis library.

#include <cstddef>
#include <vector>

#include "diagnosis/static_scene/walls.hpp"

namespace lidarcal::diagnosis::static_scene {

struct WallFit {
  double alpha0 = 0.0;            ///< range offset alpha_0, metres
  double b = 0.0;                 ///< incidence bias b, metres (0 unless fitted)
  double tau = 0.0;               ///< wall roughness, metres
  double alpha0_se = kInf;        ///< standard error of alpha_0 (0 when held)
  double b_se = kInf;             ///< standard error of b
  std::vector<Line> lines;        ///< the fitted lines, indexed by Bin::wall
  std::vector<double> loo_ll;     ///< per wall bin (order of `bins` below)
  double in_ll = 0.0;             ///< in-sample log-likelihood of the wall bins' means
  std::vector<std::size_t> bins;  ///< the wall bins
  std::vector<double> resid;      ///< bin mean minus model, per wall bin
  double rms = 0.0;               ///< RMS of resid, metres
  bool ok = false;                ///< the fit ran to its end
};

/// Fits the wall model to the bins on walls from the lines `start`; with_b: the incidence bias b
/// free (else 0); fixed_alpha0: alpha_0 held there (NaN: fitted). ok = false with too few bins.
WallFit fitWalls(const BinnedReadings& d, const std::vector<BinFit>& f,
                 const std::vector<Line>& start, bool with_b, double fixed_alpha0 = kNaN);

}  // namespace lidarcal::diagnosis::static_scene
