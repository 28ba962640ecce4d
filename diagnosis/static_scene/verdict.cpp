// SPDX-License-Identifier: BSD-3-Clause
// Step 4 of a static diagnosis after nameCause: the rules of diagnosis/rules.hpp that read the
// tails (their significance, a noise law re-ranked beside a pooled contamination, the covariate
// that names their cause, the caution when the contamination holds most readings).

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "diagnosis/rules.hpp"
#include "diagnosis/static_scene/problem.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::static_scene {
namespace {

/// The effects fitted under the pooled contamination (StaticDiagnosis::tailRobust): their key in
/// TailAttribution::robust, or nullptr.
const char* robustEffectOf(Effect e) {
  if (e == Effect::incidence_noise) return "incidence_noise_exponent";
  if (e == Effect::range_noise_law) return "noise_exponent";
  if (e == Effect::mixed_pixels) return "mixed_pixel_fraction";
  if (e == Effect::dark_surface) return "dark_noise_exponent";
  return nullptr;
}

}  // namespace

/// Rule rerank_beside_contamination: a noise law, mixed pixels or a dark surface named while the
/// tails are significant; the Gaussian likelihood the ranking came from is dominated by the tails,
/// so the four are ranked again by their held-out gains over the pooled contamination (Holm across
/// them); the largest significant one is named. False when none is significant there.
bool StaticDiagnosis::reRankUnderTails(DiagnosisResult& out) {
  named_by_tails_ = true;  // its simulation takes the exponent fitted beside the contamination
  const auto& rob = out.tails.robust;
  std::vector<Effect> effects;
  std::vector<double> p;
  for (Effect e : {Effect::incidence_noise, Effect::range_noise_law, Effect::mixed_pixels,
                   Effect::dark_surface}) {
    const std::string key = robustEffectOf(e);
    if (!rob.count(key + "_p")) continue;
    effects.push_back(e);
    p.push_back(rob.at(key + "_p"));
  }
  const auto adj = holmAdjust(p);
  std::string best;
  double best_gain = 0.0;
  for (std::size_t k = 0; k < effects.size(); ++k) {
    const double gain = rob.at(std::string(robustEffectOf(effects[k])) + "_gain");
    if (adj[k] < config_.alpha && gain > best_gain) {
      best_gain = gain;
      best = toString(effects[k]);
    }
  }
  if (best.empty()) return false;
  if (best == out.primary_cause) return true;
  out.decision = "the tails are significant and dominate the Gaussian likelihood that ranked " +
                 out.primary_cause + " first; fitted beside a pooled contamination, " + best +
                 " has the largest significant held-out gain (+" + std::to_string(best_gain) +
                 " nats per reading)";
  out.primary_cause = best;
  return true;
}

/// The rules after nameCause, in the table's order (diagnosis/rules.hpp): tails_significant,
/// rerank_beside_contamination and tails_name_cause (refineCauseByTails), contamination_caution.
void StaticDiagnosis::refineCause(DiagnosisResult& out) {
  refineCauseByTails(out);
  // Rule contamination_caution: a contamination of most readings is the main component, not a
  // tail, and what is fitted beside it describes the wild readings (docs/FINDINGS.md).
  if (named_by_tails_ && out.tails.pooled_fraction > rules::kMostReadings)
    out.decision +=
        "; caution: the pooled contamination holds " +
        std::to_string(static_cast<int>(std::lround(100.0 * out.tails.pooled_fraction))) +
        " % of the readings, so the values fitted beside it describe those readings more than the "
        "sensor's "
        "core noise: look for what the beams see besides the scene (the vehicle's body, moving "
        "objects) and "
        "leave it out (import --range-min, a shorter stretch of scans)";
}

/// Rules tails_significant, rerank_beside_contamination and tails_name_cause: when the named cause
/// is the pooled symptom (heavy_tails) or nothing while the tails are significant, the physical
/// effect whose covariate carries the largest significant share of the tails' explained
/// log-likelihood; heavy_tails, cause unknown, when none does (docs/results/static-diagnosis.md).
void StaticDiagnosis::refineCauseByTails(DiagnosisResult& out) {
  TailAttribution& ta = out.tails;
  if (!ta.fitted) return;
  // Rule tails_significant.
  double tested = 1.0;
  bool heavy = false;
  for (const auto& c : out.candidates) {
    tested += std::isfinite(c.p_value) && c.applicable;
    heavy = heavy || (c.effect == Effect::heavy_tails && c.significant);
  }
  ta.significant = heavy || std::min(1.0, tested * ta.p_value) < config_.alpha;
  if (!ta.significant) return;
  const std::optional<Effect> named = parseEffect(out.primary_cause);
  std::string why;  // why the tails' cause replaces the Gaussian ranking's
  if (named && robustEffectOf(*named)) {
    if (reRankUnderTails(out)) return;
    // None of the four is significant beside the contamination: the tails made the Gaussian
    // verdict, and the tails' own cause is named.
    named_by_tails_ = false;
    why = out.primary_cause +
          ", first under the Gaussian likelihood, is not significant beside a pooled contamination "
          "(nor is another noise "
          "law, mixed pixels or a dark surface)";
    out.primary_cause = cause::kNone;
  }
  // Rule tails_name_cause.
  if (!names(out.primary_cause, Effect::heavy_tails) && out.primary_cause != cause::kNone) return;
  if (ta.cause == cause::kUnknown) {
    if (!why.empty())
      out.decision = why;
    else if (out.primary_cause == cause::kNone)
      out.decision =
          "the tails are significant (a contamination mixture predicts held-out readings better, "
          "p " +
          std::to_string(ta.p_value) + ") but no candidate is";
    out.primary_cause = toString(Effect::heavy_tails);
    out.decision +=
        "; no covariate of the tails (edge, grazing, range, dark) explains them held out: cause "
        "unknown";
    return;
  }
  const TailCovariateResult* top = nullptr;
  for (const auto& c : ta.covariates)
    if (c.significant && names(ta.cause, c.effect) &&
        (!top || c.unique_gain_nats_per_point > top->unique_gain_nats_per_point))
      top = &c;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the tails are significant; of what their covariates explain "
                "held out (+%.4g nats per reading over a pooled contamination), `%s` carries the "
                "largest significant share "
                "(%.0f %%, +%.4g +- %.2g nats, Holm p %.2g): %s",
                ta.explained_gain_nats_per_point, top->covariate.c_str(), 100.0 * top->share,
                top->unique_gain_nats_per_point, top->unique_gain_se, top->p_holm,
                ta.cause.c_str());
  out.decision = why.empty() ? std::string(buf) : why + "; " + buf;
  out.primary_cause = ta.cause;
  named_by_tails_ = true;
  // The tail model until the named effect's candidate replaces it (every cause the tails name is a
  // candidate; dark_surface's model is the Gaussian noise law with the darkness factor, simulated
  // with the exponent fitted on all readings).
  out.extended_parameters = ta.model;
  out.gain_heldout_nats_per_point =
      ta.pooled_gain_nats_per_point + ta.explained_gain_nats_per_point;
}

}  // namespace lidarcal::diagnosis::static_scene
