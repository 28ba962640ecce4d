// SPDX-License-Identifier: BSD-3-Clause
// Step 3 of a sequence diagnosis, the scores: one candidate's held-out gain, likelihood ratio,
// p-value, identifiability and estimates, and the gates of the rule table (diagnosis/rules.hpp)
// that hold its p-value at 1 when its fit is no effect.

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "common/stats_util.hpp"
#include "diagnosis/rules.hpp"
#include "diagnosis/sequence/noise_shape.hpp"
#include "diagnosis/sequence/problem.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::sequence {

/// The gates of the rule table (diagnosis/rules.hpp), in its order: a candidate whose fit is no
/// effect gets p = 1 (or the p of its estimate), whatever its held-out gain. `lr`: twice the log
/// ratio of its fit on all the data against the baseline's in the same optimum.
void SequenceDiagnosis::applyCandidateGates(CandidateResult& r, const JointResult& fc,
                                            double lr) const {
  auto say = [&r](const std::string& why) { r.note += (r.note.empty() ? "" : "; ") + why; };
  // Rule step_scale_at_bound: a path bent by another effect runs the scale to its bound
  // (docs/results/hidden-effects.md, Robots that never stop).
  if (r.effect == Effect::odometry_scale && std::isfinite(r.p_value) &&
      std::abs(fc.effects.odometry_scale) >= kMaxStepScale * (1.0 - 1e-6)) {
    r.p_value = 1.0;
    say("its estimate ran to the bound (+-0.5): a path bent by another effect, not a step scale");
  }
  if (!baseline_fit_.motion_prior || !std::isfinite(r.p_value)) return;
  // Rule estimate_clear_of_null: the intersection-union test with the estimate's own z.
  if (r.standard_error > 0.0) {
    const double z = effectSize(r.effect, fc) / r.standard_error;
    const double p_estimate = std::erfc(z / std::sqrt(2.0));
    if (p_estimate > r.p_value) {
      r.p_value = p_estimate;
      char buf[96];
      std::snprintf(buf, sizeof buf, "its estimate is %.1f standard errors from no effect", z);
      say(buf);
    }
  }
  // Rule mixed_pixels_at_floor.
  if (r.effect == Effect::mixed_pixels &&
      fc.effects.mixed_pixel_fraction <= kMinMixedPixelFraction * (1.0 + 1e-9)) {
    r.p_value = 1.0;
    say("no reading was attributed to mixed pixels (the fraction at its floor)");
  }
  // Rule geometry_term_in_sample: a term in the mean nests the baseline, so at its optimum its fit
  // is at least as likely (lr >= 0); otherwise its held-out gain is the fold fits' other optima.
  if (geometryTerm(r.effect) && lr <= 0.0) {
    r.p_value = 1.0;
    char buf[200];
    if (lr < -2.0 * rules::kNestedSlackNats)
      std::snprintf(buf, sizeof buf,
                    "its fit on all the data is %.1f nats less likely than the baseline's: not at "
                    "its optimum",
                    -0.5 * lr);
    else
      std::snprintf(buf, sizeof buf,
                    "its fit on all the data is no more likely than the baseline's (%+.2g nats): "
                    "it explains nothing in sample",
                    0.5 * lr);
    say(buf);
  }
}

/// Rule evidence: the candidate's likelihood-ratio p and its p-value from the held-out gain, the
/// score statistic and the ratio. The ratio counts for one-parameter effects, where the baseline's
/// parameters absorb most of an effect (a constant bearing rotation moves the poles) and the
/// held-out gain is small; under the motion prior only for the path terms (two fits of a pose per
/// scan need not reach their best optimum: docs/FINDINGS.md) and, restricted over the poses, for a
/// noise exponent. A drive's path term is judged by its ratio alone: its evidence is in the
/// odometry steps, of which the held-out readings see nothing. The rounded model by its held-out
/// gain alone: its statistic shows that the grid exists, not that the rounding explains anything.
void SequenceDiagnosis::setPValue(CandidateResult& r, std::size_t c, double lr) const {
  const bool rounded = r.effect == Effect::quantisation;
  const bool ratio = !baseline_fit_.motion_prior || pathTerm(r.effect);
  const bool shape_ratio = baseline_fit_.motion_prior && restrictedShape(r.effect) &&
                           std::isfinite(shape_lr_statistic_[c]);
  r.p_likelihood_ratio = rounded       ? kNaN
                         : ratio       ? likelihoodRatioPValue(lr, r.parameters)
                         : shape_ratio ? boundedLikelihoodRatioPValue(shape_lr_statistic_[c])
                                       : kNaN;
  const bool ratio_alone =
      baseline_fit_.motion_prior && pathTerm(r.effect) && std::isfinite(r.p_likelihood_ratio);
  r.p_value = rounded       ? r.p_heldout
              : ratio_alone ? r.p_likelihood_ratio
                            : combinedPValue(r.p_heldout, r.score_p_value, r.p_likelihood_ratio);
}

CandidateResult SequenceDiagnosis::candidate(std::size_t c, const HeldOut& held,
                                             const DiagnosisResult& out) {
  CandidateResult r;
  r.effect = candidates_[c];
  r.statistic = statisticOf(r.effect, DiagnoseMode::sequence);
  setScore(r, out.battery);
  const JointResult& fc = candidate_fits_[c];
  if (!fc.ok()) {
    r.applicable = false;
    r.note = "the extended fit failed: " + fc.status.message;
    r.p_value = kNaN;
    return r;
  }
  if (const char* why = whyNotFitted(r.effect)) {
    r.applicable = false;
    r.note = why;
    r.p_value = kNaN;
    return r;
  }
  // Held-out gain per point, standard error from per-scan blocks.
  setHeldOutGain(r, heldOutGain(held, c));
  // Parameters beyond the baseline's (a continuous recording's baseline refines the headings too).
  r.parameters = fc.effect_parameters - baseline_fit_.effect_parameters;
  // In sample the rounded model's baseline is scored on the spread readings (a density at the grid
  // points themselves is not comparable with a cell probability).
  const bool rounded = r.effect == Effect::quantisation;
  double base_total = baseline_nll_in_optimum_[c];
  if (rounded) {
    double spread = 0.0;
    for (const auto& x : evaluateJoint(dequantised_, baseline_fit_, baseline_cfg_))
      spread -= x.log_likelihood;
    base_total = spread + baseline_fit_.prior_neg_log_likelihood;
  }
  const double lr = 2.0 * (base_total - fc.neg_log_likelihood - fc.prior_neg_log_likelihood);
  r.delta_aic = 2.0 * r.parameters - lr;
  setPValue(r, c, lr);
  setIdentifiability(r, fc, out.radius_known);
  applyCandidateGates(r, fc, lr);
  r.estimates = effectEstimates(r.effect, fc);
  if (truth_) r.calibration_mse_ratio = calibrationMseRatio(obs_, fc, candidate_cfgs_[c], *truth_);
  return r;
}

void SequenceDiagnosis::setIdentifiability(CandidateResult& r, const JointResult& fc,
                                           bool radius_known) const {
  if (const auto it = identifiability_.find(r.effect); it != identifiability_.end()) {
    r.information_ratio = it->second.ratio;
    r.standard_error = it->second.se;
    // Rule identifiable: estimable at the smallest size worth naming, or the estimate stands clear
    // of zero once the baseline's parameters are free.
    r.identifiable = it->second.se < std::max(it->second.ref, effectSize(r.effect, fc) /
                                                                  rules::kIdentifiableEstimateSe);
  }
  if (r.identifiable) return;
  if (r.effect == Effect::incidence_bias && !radius_known)
    r.note =
        "confounded with the landmark radius and alpha_0 (radius estimated; give "
        "landmark_radius_m)";
  else if (r.effect == Effect::odometry_scale && !radius_known)
    r.note =
        "a step-length error is a change of the world's scale, which the bias polynomial absorbs "
        "when the radius is unknown";
  else if (r.effect == Effect::mixed_pixels)
    r.note = "too few outermost or inner beams";
  else
    r.note = "the baseline's parameters absorb it (standard error " +
             std::to_string(r.standard_error) + " after them)";
}

}  // namespace lidarcal::diagnosis::sequence
