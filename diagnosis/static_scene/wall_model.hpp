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
  double alpha0 = 0.0, b = 0.0, tau = 0.0;
  double alpha0_se = kInf, b_se = kInf;
  std::vector<Line> lines;
  std::vector<double> loo_ll;    ///< per wall bin (order of `bins` below)
  double in_ll = 0.0;            ///< in-sample log-likelihood of the wall bins' means
  std::vector<std::size_t> bins;  ///< the wall bins
  std::vector<double> resid;     ///< bin mean minus model, per wall bin
  double rms = 0.0;
  bool ok = false;
};

/// Fits the wall model to the bins on walls from the lines `start`; with_b: the incidence bias b
/// free (else 0); fixed_alpha0: alpha_0 held there (NaN: fitted). ok = false with too few bins.
WallFit fitWalls(const BinnedReadings& d, const std::vector<BinFit>& f, const std::vector<Line>& start, bool with_b,
                 double fixed_alpha0 = kNaN);

}  // namespace lidarcal::diagnosis::static_scene
