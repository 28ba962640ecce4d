// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Model criticism (`lidarcal diagnose`): what the published range model gets wrong on measured
// data, the physical cause, the model extended with it and the gain, measured out of sample.
//   1. fit the baseline, the published model: polynomial range bias, noise by range only
//      (Alhashimi et al. 2016 eq. 1), independent bearing and stop-position errors
//      (Alhashimi et al. 2021 A3-A4, eq. 8);
//   2. parametric bootstrap: simulate the same geometry from the fitted baseline, refit, and
//      calibrate a battery of discrepancy statistics (and one score statistic per candidate
//      effect) on the replicas: p-value and effect size of each;
//   3. fit the baseline extended by each candidate effect; gain out of sample (cross-validated
//      by scan), delta AIC, identifiability (information left after the nuisance parameters);
//   4. name the cause by the ordered rules of diagnosis/rules.hpp (docs/DIAGNOSIS.md): the
//      largest significant held-out gain, Holm-controlled across candidates; `none` when nothing
//      is significant, `not_identifiable` when the data cannot tell; a symptom (heavy tails, a
//      reading grid) gives way to the physical effect that holds beside it;
//   5. the extended model: its parameters, the scene keys that simulate it, how much closer its
//      simulation comes to the data, and (with truth) the gain in calibration.
// Two kinds of data: a sequence of scans of poles (diagnosis/sequence.hpp) and repeated scans
// from one pose of any scene (diagnosis/static_scene.hpp), both run by the same five steps
// (diagnosis/skeleton.hpp). The statistics are in diagnosis/stats.hpp and diagnosis/battery.hpp.

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "common/effect.hpp"
#include "common/range_model.hpp"
#include "common/status.hpp"

namespace lidarcal::diagnosis {

/// The verdicts that are not an effect (DiagnosisResult::primary_cause, TailAttribution::cause);
/// the effects themselves are lidarcal::Effect (common/effect.hpp).
namespace cause {
inline constexpr const char* kNone = "none";  ///< nothing significant
/// significant, but the data cannot tell which
inline constexpr const char* kNotIdentifiable = "not_identifiable";
inline constexpr const char* kUnknown = "unknown";  ///< tails: no covariate explains them
}  // namespace cause
/// Whether a verdict (primary_cause, TailAttribution::cause) names the effect.
inline bool names(const std::string& verdict, Effect e) { return verdict == toString(e); }

enum class DiagnoseMode { sequence, static_scene };
const char* toString(DiagnoseMode mode);  ///< "sequence" or "static"

struct DiagnoseConfig {
  int replicas = 19;       ///< parametric bootstrap replicas (each is one baseline refit)
  int folds = 3;           ///< cross-validation folds (by scan)
  double alpha = 0.01;     ///< family-wise error rate over the candidates (Holm)
  std::uint64_t seed = 1;  ///< bootstrap and simulation seed
  int max_order = 4;  ///< sequences: bias orders 1..max_order (order by the calibration's rule)
  /// Sequences: odometry, std. dev. of a stop's position around the commanded one, metres
  /// (Alhashimi et al. 2021 eq. 8).
  double sigma_s_m = 0.02;
  double outlier_floor = 1e-3;  ///< weight of a uniform over the reading window in every likelihood
  /// replicas simulated from the extended model (closeness to the data)
  int closeness_replicas = 4;
  /// Static data: scans per window. 0: the whole recording is one pose unless the beams show that
  /// the sensor moved (then windows of 8 scans, each with a time trend per beam); -1: never
  /// windows.
  int static_window = 0;
  /// Static data: the range offset alpha_0 when known from elsewhere (a reference distance);
  /// NaN: estimated from the straightness of the walls (then an incidence-dependent bias, which
  /// bends walls much alike, is hard to tell from it).
  double static_range_offset_m = std::numeric_limits<double>::quiet_NaN();
  std::vector<Effect> candidates;  ///< effects to test; empty: every candidate of the mode
  /// Optional: hears of each step (stage name, units done, total; total 0: not counted). Only
  /// reports; the result does not depend on it.
  std::function<void(const std::string& stage, std::size_t done, std::size_t total)> progress;
  void validate() const;  ///< throws std::invalid_argument
};

/// The candidates a diagnosis of that mode tests: `config.candidates`, or every effect the mode
/// tests (those with a statistic for it in effectTable()) when empty. Throws std::invalid_argument
/// for an effect the mode does not test.
std::vector<Effect> candidateList(const DiagnoseConfig& config, DiagnoseMode mode);

/// One discrepancy statistic: measured value against its distribution over the replicas.
struct Discrepancy {
  std::string name;           ///< e.g. "spread_vs_incidence"
  std::string variable;       ///< what the residuals are compared against
  std::string description;    ///< how it is computed, with its unit
  double value = 0.0;         ///< on the measured data
  double replica_mean = 0.0;  ///< over the bootstrap replicas
  double replica_sd = 0.0;
  double effect_size = 0.0;  ///< (value - replica_mean) / replica_sd
  double p_value = 1.0;      ///< from the replicas (Student-t predictive, see diagnose_stats.hpp)
  bool two_sided = true;     ///< both directions count (else only values above the replicas)
};

/// One candidate effect.
struct CandidateResult {
  Effect effect = Effect::incidence_noise;  ///< the effect tested
  /// p-value of the effect: m min(p of the held-out gain, p of the score statistic aimed at it,
  /// p of the likelihood ratio where it applies) over the m tests that apply (Bonferroni); a
  /// continuous recording's path term: its likelihood ratio's alone. NaN when none applies.
  double p_value = 1.0;
  double p_heldout = 1.0;  ///< one-sided p of the held-out gain over its standard error (normal)
  /// Sequence mode, one-parameter effects: p of the likelihood ratio on all the data (chi-square,
  /// 1 degree of freedom); on a continuous recording the path terms' only, and the noise
  /// exponents' restricted ratio over the poses (half chi-square: the null on the bound); NaN
  /// otherwise.
  double p_likelihood_ratio = std::numeric_limits<double>::quiet_NaN();
  double p_holm = 1.0;         ///< Holm-adjusted across the candidates with a p-value
  std::string statistic;       ///< the battery's score statistic aimed at this effect
  double score_p_value = 1.0;  ///< its p-value, calibrated on the bootstrap replicas
  double effect_size = 0.0;    ///< its effect size, in replica standard deviations
  /// mean held-out log-likelihood gain over the baseline
  double heldout_gain_nats_per_point = 0.0;
  double heldout_gain_se = 0.0;  ///< its standard error (blocks: scans)
  double delta_aic = 0.0;        ///< AIC(extended) - AIC(baseline); negative favours the effect
  int parameters = 0;            ///< parameters the effect adds
  bool significant = false;      ///< Holm p < alpha and a positive held-out gain (see nameCause)
  bool identifiable = true;      ///< the data can estimate it apart from the baseline's parameters
  bool applicable = true;        ///< the data can show it at all (e.g. no heading in a static scan)
  double information_ratio = 1.0;  ///< information kept after the nuisance parameters (0..1)
  /// Standard error of the effect's parameter once the baseline's parameters are profiled out
  /// (unit of its estimate; RMS over components). Identifiable: below the smallest size worth
  /// naming (1 cm, 1 degree, 1 % of the step, 0.5 in an exponent, 1 cm of drift over the data),
  /// or below a quarter of the estimate (it stands clear of zero apart from the baseline).
  double standard_error = 0.0;
  std::string note;  ///< why not identifiable / not applicable / competing effect
  /// the effect's fitted parameters (name with unit -> value)
  std::map<std::string, double> estimates;
  /// With truth: MSE ratio (Alhashimi et al. 2021 eq. 31) of the extended calibration, 0 when not
  /// computed.
  double calibration_mse_ratio = 0.0;
};

/// How close a simulation of a model comes to the measured data.
struct Closeness {
  /// two-sample Kolmogorov-Smirnov distance of the standardised residuals
  double ks_distance = 0.0;
  /// Median over groups of |ln(measured / simulated residual variance)| (0: the spreads match)
  double variance_ratio_median_abs_log = 0.0;
  std::size_t groups = 0;  ///< groups compared (sequence: landmark x stop x edge; static: beams)
};

/// One residual of the measured data (or of a replica), with what it may depend on.
struct ResidualRecord {
  double range_m = 0.0;        ///< predicted true distance (sequence) or mean reading (static)
  double incidence_rad = 0.0;  ///< incidence on the surface
  /// sequence: signed position across the pole (-1..1); static: 1 at a depth discontinuity
  double lateral = 0.0;
  int group = 0;      ///< landmark id (sequence) or wall id (static, 0: not on a fitted wall)
  double time = 0.0;  ///< scan index
  double bearing_rad = 0.0;  ///< beam angle in the sensor frame
  int stop = 0;              ///< stop index (sequence)
  bool edge = false;         ///< at a depth discontinuity
  double residual_m = 0.0;   ///< reading minus the baseline's prediction
  double z = 0.0;            ///< residual over the baseline's standard deviation
};

/// One covariate of the tail model (diagnosis/tails.hpp): how much of the tails it explains.
struct TailCovariateResult {
  std::string covariate;  ///< edge, grazing, range or dark
  /// the physical effect it stands for (mixed_pixels, incidence_noise, range_noise_law,
  /// dark_surface)
  Effect effect = Effect::mixed_pixels;
  /// its beta in logit pi (fitted on all the data, per unit of the covariate)
  double coefficient = 0.0;
  /// held-out gain of the full tail model over the model without it
  double unique_gain_nats_per_point = 0.0;
  double unique_gain_se = 0.0;  ///< its standard error (blocks: scans)
  double p_value = 1.0;         ///< one-sided p of that gain
  double p_holm = 1.0;          ///< Holm-adjusted across the covariates
  double share = 0.0;  ///< unique gain over the explained gain (full tail model vs the pooled one)
  bool significant = false;  ///< Holm p < alpha and a positive gain
};

/// One beam among those that carry the tails.
struct TailBeamReport {
  double bearing_rad = 0.0;    ///< beam angle in the sensor frame
  double range_m = 0.0;        ///< its mean reading
  double incidence_rad = 0.0;  ///< NaN when unknown
  double intensity = 0.0;      ///< mean intensity of its readings (NaN: none recorded)
  bool edge = false;           ///< at a depth discontinuity
  std::size_t readings = 0;    ///< its readings
  /// mean posterior probability of its readings being in the broad component
  double tail_fraction = 0.0;
  double tail_probability = 0.0;  ///< the fitted pi of the beam (from its covariates)
  std::string cls;                ///< class: edge, grazing, range, dark or unknown
};

/// Static mode: the tails explained by physical covariates (diagnosis/tails.hpp).
struct TailAttribution {
  bool fitted = false;  ///< false: not run (note says why)
  std::string note;
  double pooled_fraction = 0.0;    ///< pi of the pooled contamination model (all data)
  double pooled_wide_scale = 0.0;  ///< k of the pooled model (broad over core standard deviation)
  /// held out: pooled contamination over the Gaussian baseline
  double pooled_gain_nats_per_point = 0.0;
  double pooled_gain_se = 0.0;
  /// held out: the model with every covariate over the pooled one
  double explained_gain_nats_per_point = 0.0;
  double explained_gain_se = 0.0;
  /// One-sided p of the held-out gain of the full tail model over the Gaussian baseline; the tails
  /// are significant when heavy_tails is, or when this p times (candidates tested + 1) < alpha.
  double p_value = 1.0;
  bool significant = false;  ///< the tails are significant (rule above)
  /// those the data have (edge, grazing, range, dark)
  std::vector<TailCovariateResult> covariates;
  /// expected readings in the broad component (sum of posteriors, all data)
  double tail_readings = 0.0;
  /// the same by class of beam (edge, grazing, range, dark, unknown)
  std::map<std::string, double> tail_readings_by_class;
  std::map<std::string, double> readings_by_class;  ///< all readings by class of beam
  std::vector<TailBeamReport> top_beams;  ///< beams with the largest tail fraction (at most 10)
  /// the full tail model's parameters (name with unit -> value)
  std::map<std::string, double> model;
  /// Physical effects fitted under the pooled contamination likelihood (the tails do not drag
  /// them): incidence_noise_exponent, noise_exponent, mixed_pixel_fraction, dark_noise_exponent,
  /// and their held-out gains over the pooled model (..._gain, ..._gain_se, nats per reading).
  std::map<std::string, double> robust;
  /// the effect of the covariate with the largest significant unique gain, or unknown
  std::string cause = cause::kUnknown;
};

struct DiagnosisResult {
  Status status;  ///< ok, or why the data cannot be diagnosed and what to do about it
  DiagnoseMode mode = DiagnoseMode::sequence;
  // Data
  std::size_t scans = 0, stops = 0, readings = 0;  ///< size of the data diagnosed
  std::size_t landmarks = 0;                       ///< sequence: landmarks; static: fitted walls
  // Baseline
  RangeModel baseline;  ///< bias f, noise law (Alhashimi et al. 2016, squared), window
  double baseline_sigma_theta_rad = 0.0;         ///< sequence: bearing noise of the sightings
  double baseline_radius_m = 0.0;                ///< sequence: landmark radius
  bool radius_known = false;                     ///< sequence: radius given (not estimated)
  double baseline_neg_log_likelihood = 0.0;      ///< in-sample, nats
  double baseline_heldout_nats_per_point = 0.0;  ///< held-out log-likelihood per point
  /// further fitted quantities (name with unit -> value)
  std::map<std::string, double> baseline_extra;
  // Tests
  std::vector<Discrepancy> battery;         ///< discrepancy statistics
  std::vector<CandidateResult> candidates;  ///< one per candidate effect
  /// an effect's name (toString(Effect)), none or not_identifiable
  std::string primary_cause = cause::kNone;
  std::string decision;   ///< why that cause (rule applied, competing effects)
  TailAttribution tails;  ///< static mode: what the tails are made of
  // Extended model
  std::map<std::string, double> extended_parameters;  ///< the named effect's parameters
  std::map<std::string, double> scene_keys;  ///< scene JSON keys (docs/FORMAT.md) that simulate it
  std::vector<double> extended_bias_alpha;   ///< bias of the extended fit
  Closeness closeness_baseline;              ///< baseline simulation vs the data
  Closeness closeness_extended;              ///< extended simulation vs the data
  double gain_heldout_nats_per_point = 0.0;  ///< of the named effect
  double gain_delta_aic = 0.0;               ///< of the named effect
  /// with truth: MSE ratio of the baseline calibration (0: no truth)
  double calibration_mse_ratio_baseline = 0.0;
  double calibration_mse_ratio_extended = 0.0;  ///< with truth: of the extended calibration
  // Plot data
  std::vector<ResidualRecord> measured;            ///< residuals of the data under the baseline
  std::vector<ResidualRecord> simulated_baseline;  ///< of one baseline replica (refitted)
  /// of one extended replica (refitted with the baseline)
  std::vector<ResidualRecord> simulated_extended;
  std::uint64_t seed = 0;  ///< seed used
  int replicas = 0;        ///< bootstrap replicas used
  int folds = 0;           ///< folds used
};

}  // namespace lidarcal::diagnosis
