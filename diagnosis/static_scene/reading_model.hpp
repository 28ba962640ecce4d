// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The reading model: each reading of a bin about its location, with the noise law
// sigma_e |m|^kappa (1 / cos phi)^gamma (I_ref / I)^delta (Alhashimi et al. 2016 eq. 1 with free
// exponents), a drift, mixed pixels at depth edges, Student-t tails or rounding to a grid; its
// predictive log-likelihood and the fit of its free terms. Internal to the diagnosis library.

#include <cstddef>
#include <vector>

#include "common/effect.hpp"
#include "diagnosis/static_scene/bins.hpp"

namespace lidarcal::diagnosis::static_scene {

/// A reading model's parameters (the baseline: the squared law, Gaussian, no drift).
struct ReadingModel {
  /// scale of sigma = sigma_e |m|^kappa (1 / cos phi)^gamma (I_ref / I)^delta
  double sigma_e = 0.01;
  double kappa = 2.0;         ///< range exponent (Alhashimi et al. 2016: 2)
  double gamma = 0.0;         ///< incidence exponent
  double delta = 0.0;         ///< dark-surface exponent: sigma times (I_ref / I)^delta
  double drift = 0.0;         ///< metres per scan
  double mixed = 0.0;         ///< fraction of mixed readings at edge bins
  double dof = 0.0;           ///< Student t degrees of freedom (0: Gaussian)
  double q = 0.0;             ///< quantisation step (0: densities)
  bool robust_edges = false;  ///< edge bins centred on their median (mixed-pixel model)
};

/// Which terms of the reading model are free (one per candidate effect).
struct FreeTerms {
  bool kappa = false;   ///< range exponent (range_noise_law)
  bool gamma = false;   ///< incidence exponent (incidence_noise)
  bool drift = false;   ///< drift over the scans (range_drift)
  bool mixed = false;   ///< mixed-pixel fraction at edges (mixed_pixels)
  bool dof = false;     ///< Student-t degrees of freedom (heavy_tails)
  bool quant = false;   ///< rounding to the detected grid (quantisation)
  bool wall_b = false;  ///< the wall model's incidence bias (incidence_bias)
  bool delta = false;   ///< dark-surface exponent (dark_surface)
  int parameters() const { return kappa + gamma + drift + mixed + dof + quant + wall_b + delta; }
};

/// The terms effect e frees (none for an effect the reading model has no term for).
FreeTerms freeTermsOf(Effect e);

/// The noise law's shape at location `loc` of bin b: sigma = sigma_e times this.
double shapeOf(const ReadingModel& m, const Bin& b, double loc);

/// The bin's centre: its median at an edge under the mixed-pixel model, else its mean.
double centreOf(const ReadingModel& m, const Bin& b, const BinFit& f);

/// Where a reading at angle a in scan t is expected (without the drift term).
double expected(const ReadingModel& m, const Bin& b, const BinFit& f, double a, double t);

/// Log-likelihood of one reading (predictive: the bin's location is known to 1 / n_train).
double readingLL(const ReadingModel& m, const BinnedReadings& d, const Bin& b, const BinFit& f,
                 std::size_t i, double floor_weight);

/// Fits the free parameters of a model on the readings of the training scans (`fits`: the bin
/// locations it ends with).
ReadingModel fitModel(const BinnedReadings& d, const std::vector<bool>& train, const FreeTerms& fl,
                      double q_detected, std::vector<BinFit>& fits);

}  // namespace lidarcal::diagnosis::static_scene
