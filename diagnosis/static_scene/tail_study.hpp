// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The tails of a static recording explained (diagnosis/tails.hpp): the contamination model's
// covariates per bin, the residuals it is fitted to, and its variants (pooled, every covariate,
// one left out at a time, the robust effects) compared on the same scan folds. Internal to the
// diagnosis library.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "diagnosis/held_out.hpp"
#include "diagnosis/static_scene/bins.hpp"
#include "diagnosis/tails.hpp"

namespace lidarcal::diagnosis::static_scene {

/// The tail model's view of the bins: covariates from the full-data locations `f`.
std::vector<TailBeam> tailBeams(const BinnedReadings& d, const std::vector<BinFit>& f);

/// Covariates the data can show: edges at 3 beams or more; the others varying over 3 beams or more.
std::array<bool, kTailCovariates> tailAvailable(const BinnedReadings& d,
                                                const std::vector<TailBeam>& beams,
                                                std::size_t edges);

/// Residuals of the readings about their bin's location (edge bins: about the median, as a
/// mixed-pixel model needs), of the training scans or of the held-out ones; `scans` gets each
/// one's scan. Held out: the location's uncertainty widens the core (factor sqrt(1 + 1/n)).
std::vector<TailReading> tailResiduals(const BinnedReadings& d, const std::vector<BinFit>& f,
                                       const std::vector<bool>& train, bool held_out,
                                       std::vector<std::size_t>* scans);

/// The tail models compared, their held-out log-likelihoods (aligned with the Gaussian
/// baseline's held-out readings) and the scan of each point.
struct TailStudy {
  std::vector<TailBeam> beams;                    ///< every bin as the tail model sees it
  std::array<bool, kTailCovariates> available{};  ///< covariates the data can show
  /// 0: pooled, 1: every covariate, then one without each, then robust effects
  std::vector<TailSpec> specs;
  std::vector<int> dropped;  ///< covariate left out of spec s (-1: none)
  /// specs of the robust effects (0: not fitted)
  std::size_t gamma = 0, kappa = 0, mixed = 0, delta = 0;
  std::vector<std::vector<double>> ll;  ///< per spec, held-out log-likelihood of each point
  std::vector<std::size_t> block;       ///< each point's scan
  std::vector<double> gauss;   ///< the Gaussian baseline's held-out log-likelihoods, aligned
  double floor_w = 0.0;        ///< weight of the uniform outlier floor
  double floor_density = 0.0;  ///< its density over the reading window, 1/m
};

/// The specs: pooled, full, full without each covariate, pooled with each robust effect.
void setupTailSpecs(TailStudy& ts, bool incidence_known, bool edges, bool dark);

/// Held-out gain of log-likelihoods `a` over `b` (blocks: scans).
HeldOutGain gainOf(const std::vector<double>& a, const std::vector<double>& b,
                   const std::vector<std::size_t>& block);

/// Class of a beam: the significant covariate whose term raises its tail odds most (at least
/// twofold), else unknown.
std::string tailClass(const TailModel& m, const TailBeam& b,
                      const std::vector<TailCovariateResult>& covs);

}  // namespace lidarcal::diagnosis::static_scene
