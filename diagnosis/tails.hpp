// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Tails explained by physical covariates: a per-reading contamination mixture whose
// probability depends on what the beam sees. A residual r of beam b (reading minus the beam's
// location) has the density
//   p(r) = (1 - eta_b) [(1 - pi_b) N(r; 0, s_b^2) + pi_b N(r; 0, w_b^2)] + eta_b U(r; lo_b, hi_b)
//   s_b = sigma_e m_b^kappa (1 / cos phi_b)^gamma (I_med / I_b)^delta   Alhashimi et al. 2016 eq.
//   1, free exponents
//   w_b = k s_b (m_b / m_ref)^(rho - kappa)              the broad width, its own range law
//   logit pi_b = beta_0 + sum_j beta_j x_bj              x: depth edge, ln(1/cos phi), ln m,
//   darkness
// k the broad component's width over the core's at the reference range m_ref (>= 4), rho its
// range exponent (wild readings need not grow with range as the core noise does: a fixed width in
// metres is rho = 0, a scale mixture of the core rho = kappa), eta_b the mixed-pixel fraction at
// depth edges (a reading anywhere between the two surfaces; 0 elsewhere). With every beta_j = 0 the
// broad component is a pooled tail (a symptom, like a Student t); a covariate with a significant
// beta_j names a cause. Fitted by EM: closed-form sigma_e and eta, ternary search on the exponents
// and k (profile in sigma_e, per-beam sums), Newton steps (IRLS) on beta with the responsibilities
// as soft labels. Internal to the diagnosis library (static mode).

#include <array>
#include <cstddef>
#include <vector>

#include "common/effect.hpp"

namespace lidarcal::diagnosis {

/// Covariates of the contamination probability, in output order.
inline constexpr int kTailCovariates = 4;
enum TailCovariate : int { kTailEdge = 0, kTailGrazing = 1, kTailRange = 2, kTailDark = 3 };
/// "edge", "grazing", "range", "dark".
const char* tailCovariateName(int k);
/// The physical effect each covariate stands for: mixed_pixels, incidence_noise, range_noise_law,
/// dark_surface.
Effect tailCovariateEffect(int k);

/// One beam (direction bin) as the tail model sees it.
struct TailBeam {
  double log_range = 0.0;    ///< ln of the beam's mean reading (m)
  double log_sec_inc = 0.0;  ///< ln(1 / cos phi), 0 when the incidence is unknown
  /// covariates: edge 0/1, ln(1/cos phi), ln m - mean, darkness ln(I_med / I) >= 0
  std::array<double, kTailCovariates> x{};
  /// residuals a mixed reading can take (edge beams; lo == hi: none), metres
  double mix_lo = 0.0, mix_hi = 0.0;
  /// ln(I_med / I), signed (the core's dark-surface factor; 0 without intensities)
  double dark = 0.0;
};

/// One reading's residual.
struct TailReading {
  std::size_t beam = 0;     ///< index into the beams
  double residual_m = 0.0;  ///< reading minus the beam's location, metres
  /// factor on s_b (held out: sqrt(1 + 1/n) for the location's uncertainty)
  double inflation = 1.0;
};

/// Which parameters are free.
struct TailSpec {
  std::array<bool, kTailCovariates> covariate{};  ///< beta_j free (else 0)
  bool kappa = false;      ///< range exponent free (else 2, Alhashimi et al. 2016)
  bool gamma = false;      ///< incidence exponent free (else 0)
  bool mixed = false;      ///< mixed-pixel fraction at edges free (else 0)
  bool delta = false;      ///< dark-surface exponent free (else 0)
  int parameters() const;  ///< free parameters besides sigma_e, k and beta_0
};

/// The fitted model.
struct TailModel {
  double sigma_e = 0.01;  ///< noise scale, metres at 1 m
  double kappa = 2.0;     ///< range exponent
  double gamma = 0.0;     ///< incidence exponent
  double delta = 0.0;     ///< dark-surface exponent
  double wide = 5.0;      ///< k: the broad component's width over the core's at the reference range
  double wide_exponent = 2.0;  ///< rho: range exponent of the broad width
  double ref_log_range = 0.0;  ///< ln m_ref: mean ln range of the readings fitted
  double mixed = 0.0;          ///< eta: mixed-pixel fraction at edge beams
  /// logit intercept, then the covariates' coefficients
  std::array<double, 1 + kTailCovariates> beta{};
  TailSpec spec;           ///< what was free
  int iterations = 0;      ///< EM iterations run
  bool converged = false;  ///< log-likelihood change below 1e-6 nats per reading

  double tailProbability(const TailBeam& b) const;  ///< pi_b
  double sigma(const TailBeam& b) const;            ///< s_b, metres
  double broadSigma(const TailBeam& b) const;       ///< w_b, metres
  /// Log density of a residual, with a uniform floor of weight floor_w and density floor_density.
  double logDensity(const TailBeam& b, double residual_m, double inflation, double floor_w,
                    double floor_density) const;
  /// Posterior probability that the residual came from the broad component.
  double responsibility(const TailBeam& b, double residual_m, double inflation, double floor_w,
                        double floor_density) const;
};

/// Fits the model by EM (sigma_e_start is the initial scale; the other free parameters start at a
/// 2 % pooled tail of width 5, eta 5 %; or, with `start_from`, at that fitted model's parameters,
/// those `spec` holds fixed reset). Deterministic. No readings: the start, converged = false.
TailModel fitTailModel(const std::vector<TailBeam>& beams, const std::vector<TailReading>& readings,
                       const TailSpec& spec, double sigma_e_start, double floor_w,
                       double floor_density, int max_iterations = 60,
                       const TailModel* start_from = nullptr);

}  // namespace lidarcal::diagnosis
