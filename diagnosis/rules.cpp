// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/rules.hpp"

#include <cmath>
#include <limits>

#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis {

namespace {

/// Each candidate's p-value (step 3).
std::vector<VerdictRule> candidateRules() {
  return {
      {"evidence", "both", "candidate",
       "p = k min(p_heldout, p_score, p_lr) over the k tests that apply; a reading grid: p_heldout "
       "alone; a drive's "
       "path term: p_lr alone",
       "-",
       "held out where the baseline bent to absorb the effect, the score where few readings carry "
       "it, the ratio where "
       "the baseline's parameters absorb most of it"},
      {"step_scale_at_bound", "sequence", "candidate", "an odometry scale at its bound: p = 1",
       "|s| = 0.5 (kMaxStepScale)",
       "a path bent by another effect runs the scale to its bound; no odometry is that far off"},
      {"estimate_clear_of_null", "drive", "candidate",
       "p raised to the two-sided p of the estimate over its standard error", "-",
       "held-out readings of a drive differ between fits of one model by more than an effect at "
       "its null changes them"},
      {"mixed_pixels_at_floor", "drive", "candidate",
       "a mixed-pixel fraction at the EM's floor: p = 1", "1e-4 (kMinMixedPixelFraction)",
       "no reading was attributed to mixed pixels: the baseline's model"},
      {"geometry_term_in_sample", "drive", "candidate",
       "a term of the geometry whose fit on all the data is no more likely than the baseline's: p "
       "= 1",
       "2 ln ratio <= 0 (kNestedSlackNats 0.5 tells short of its optimum)",
       "it explains nothing of the data it was fitted on; its held-out gain is the folds' other "
       "optima"},
      {"dark_follows_range", "static", "candidate",
       "a dark surface whose darkness follows ln range over the beams is not identifiable",
       "|correlation| > 0.95 (kConfounded)", "the two covariates then say the same"}};
}

/// The shared naming (step 4, nameCause).
std::vector<VerdictRule> namingRules() {
  return {
      {"significant", "both", "name",
       "Holm-adjusted p < alpha across the candidates, and a positive held-out gain", "alpha",
       "the family-wise error stays at alpha, and the extended model must predict new data better"},
      {"largest_gain", "both", "name",
       "none when no candidate is significant; else the significant one with the largest "
       "held-out gain",
       "-", "the held-out gain is what the extended model buys out of sample"},
      {"parsimony", "both", "name",
       "a significant effect nested in the first one (an angle offset in per-stop headings), its "
       "gain within 2 standard "
       "errors, is named instead",
       "2 SE (kCloseGainSe)", "fewer parameters explain as much"},
      {"identifiable", "both", "name",
       "the named effect's standard error, once the baseline's parameters are free, must be below "
       "the smallest size worth "
       "naming or a quarter of its estimate; else not_identifiable",
       "4 SE (kIdentifiableEstimateSe)",
       "the data must tell the effect from the baseline's own parameters"},
      {"indistinguishable", "both", "name",
       "another significant effect within 2 standard errors, the pair declared indistinguishable: "
       "not_identifiable (no "
       "pair is declared at present)",
       "2 SE (kCloseGainSe)",
       "two effects that explain the data equally well cannot be told apart"}};
}

/// After the naming (step 4, each mode's refineCause).
std::vector<VerdictRule> refineRules() {
  return {
      {"grid_first", "sequence", "refine",
       "quantisation named: each significant identifiable physical effect is refitted beside the "
       "rounding; the largest "
       "held-out gain with p times the effects tried < alpha is named (the in-sample ratio counts "
       "too on a fine grid)",
       "alpha; fine grid: q <= 2 x the 10th-percentile noise (kFineGridOverNoise)",
       "a reading grid is the format of the output, which biases nothing"},
      {"tails_first", "sequence", "refine",
       "heavy_tails named: the same beside the Student t; the tails remain beside the effect named",
       "alpha", "heavy tails are a symptom; the named cause must be physical"},
      {"noise_term_beside_path", "drive", "refine",
       "a noise term named while a path term (angle offset, step scale) is significant must gain "
       "beside it (one-sided), "
       "else the path term is named",
       "alpha",
       "a path the fit cannot follow leaves its misfit in the readings that move most with the "
       "pose"},
      {"tails_significant", "static", "refine",
       "the tails are significant when heavy_tails is, or when the tail model's held-out p times "
       "(candidates tested + 1) "
       "< alpha",
       "alpha", "the tails must be a departure from the baseline, not a chance one"},
      {"rerank_beside_contamination", "static", "refine",
       "a noise law, mixed pixels or a dark surface named while the tails are significant is "
       "ranked again by its held-out "
       "gain beside a pooled contamination (Holm); none significant there: none, and the next rule",
       "alpha", "the tails dominate the Gaussian likelihood that ranked it first"},
      {"tails_name_cause", "static", "refine",
       "heavy_tails or none named while the tails are significant: the effect of the tail "
       "covariate (edge, grazing, range, "
       "dark) with the largest significant unique held-out gain (Holm); none: heavy_tails, cause "
       "unknown",
       "alpha", "a symptom gives way to the physical effect that explains it"},
      {"contamination_caution", "static", "refine",
       "named from the tails while the pooled contamination holds most readings: a caution is "
       "added to the decision",
       "share > 0.5 (kMostReadings)",
       "then it is the main component, and what is fitted beside it describes the wild readings"}};
}

}  // namespace

const std::vector<VerdictRule>& verdictRules() {
  static const std::vector<VerdictRule> table = [] {
    std::vector<VerdictRule> rules = candidateRules();
    for (auto part : {namingRules(), refineRules()})
      rules.insert(rules.end(), part.begin(), part.end());
    return rules;
  }();
  return table;
}

std::string nameCause(std::vector<CandidateResult>& cands, double alpha, std::string& decision,
                      const std::vector<std::pair<Effect, Effect>>& nested,
                      const std::vector<std::pair<Effect, Effect>>& indistinguishable) {
  // Rule significant.
  std::vector<double> p;
  for (const auto& c : cands)
    p.push_back(c.applicable ? c.p_value : std::numeric_limits<double>::quiet_NaN());
  const auto adj = holmAdjust(p);
  for (std::size_t i = 0; i < cands.size(); ++i) {
    cands[i].p_holm = adj[i];
    const double gain = cands[i].heldout_gain_nats_per_point;
    cands[i].significant =
        cands[i].applicable && std::isfinite(adj[i]) && adj[i] < alpha && gain > 0.0;
  }
  // Rule largest_gain.
  std::vector<std::size_t> sig;
  for (std::size_t i = 0; i < cands.size(); ++i)
    if (cands[i].significant) sig.push_back(i);
  if (sig.empty()) {
    decision = "no candidate is significant (Holm-adjusted p < " + std::to_string(alpha) +
               " with a positive held-out gain): the baseline describes the data";
    return cause::kNone;
  }
  std::size_t top = sig.front();
  for (std::size_t i : sig)
    if (cands[i].heldout_gain_nats_per_point > cands[top].heldout_gain_nats_per_point) top = i;
  decision = std::string("largest held-out gain among the significant effects: ") +
             toString(cands[top].effect);
  auto close = [&](std::size_t a, std::size_t b) {
    const double se = std::hypot(cands[a].heldout_gain_se, cands[b].heldout_gain_se);
    return cands[b].heldout_gain_nats_per_point >=
           cands[a].heldout_gain_nats_per_point - rules::kCloseGainSe * se;
  };
  // Rule parsimony: a significant effect nested in the top one that explains as much.
  std::size_t chosen = top;
  for (std::size_t i : sig)
    for (const auto& [simpler, richer] : nested)
      if (i != top && cands[i].effect == simpler && cands[top].effect == richer && close(top, i))
        chosen = i;
  if (chosen != top)
    decision =
        std::string(toString(cands[chosen].effect)) + " explains as much as " +
        toString(cands[top].effect) +
        " (held-out gains within two standard errors), which contains it, with fewer parameters";
  // Rule identifiable.
  if (!cands[chosen].identifiable) {
    decision = std::string(toString(cands[chosen].effect)) +
               " is significant but cannot be estimated apart from the baseline's parameters (" +
               cands[chosen].note + ")";
    return cause::kNotIdentifiable;
  }
  // Rule indistinguishable.
  for (std::size_t i : sig) {
    if (i == chosen || !close(chosen, i)) continue;
    for (const auto& [a, b] : indistinguishable)
      if ((a == cands[i].effect && b == cands[chosen].effect) ||
          (b == cands[i].effect && a == cands[chosen].effect)) {
        decision =
            std::string(toString(cands[chosen].effect)) + " and " + toString(cands[i].effect) +
            " are both significant, explain the data equally well and cannot be told apart here";
        return cause::kNotIdentifiable;
      }
  }
  return toString(cands[chosen].effect);
}

}  // namespace lidarcal::diagnosis
