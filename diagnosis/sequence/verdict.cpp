// SPDX-License-Identifier: BSD-3-Clause
// Step 4 of a sequence diagnosis after nameCause: the rules of diagnosis/rules.hpp that replace a
// symptom (the reading grid, heavy tails) by the physical effect that holds beside it, and that
// make a noise term hold beside a significant path term on a continuous recording.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <tuple>

#include "common/stats_util.hpp"
#include "diagnosis/rules.hpp"
#include "diagnosis/sequence/folds.hpp"
#include "diagnosis/sequence/held_out.hpp"
#include "diagnosis/sequence/noise_shape.hpp"
#include "diagnosis/sequence/problem.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::sequence {

/// The rules after nameCause, in the table's order (diagnosis/rules.hpp): grid_first, tails_first,
/// noise_term_beside_path.
void SequenceDiagnosis::refineCause(DiagnosisResult& out) {
  if (names(out.primary_cause, Effect::quantisation))
    nameCauseBesideSymptom(out, Effect::quantisation);
  if (names(out.primary_cause, Effect::heavy_tails))
    nameCauseBesideSymptom(out, Effect::heavy_tails);
  requireNoiseTermToHoldBesidePath(out);
}

/// Rule noise_term_beside_path: under the motion prior a path the fit cannot follow (a lidar yawed
/// on the robot) leaves its misfit in the readings that move most with the pose, a thin pole's
/// outermost beams, where a noise term can outgain the path term (docs/results/hidden-effects.md,
/// Robots that never stop). A path term's evidence is in the odometry steps, which no noise term
/// predicts; so a noise term named while a path term is significant must hold beside it (its
/// held-out gain over the path term alone significant, one-sided), else the path term is named.
/// Not for the terms of the geometry, which bend the path themselves.
void SequenceDiagnosis::requireNoiseTermToHoldBesidePath(DiagnosisResult& out) const {
  if (!baseline_fit_.motion_prior) return;
  const std::size_t none = out.candidates.size();
  std::size_t named = none, path = none;
  for (std::size_t c = 0; c < out.candidates.size(); ++c) {
    const CandidateResult& r = out.candidates[c];
    if (names(out.primary_cause, r.effect)) named = c;
    if (pathTerm(r.effect) && r.significant && r.identifiable &&
        (path == none || r.p_holm < out.candidates[path].p_holm))
      path = c;
  }
  if (named == none || path == none || !noiseShapeEffect(candidates_[named]) ||
      candidates_[named] == Effect::heavy_tails)
    return;
  std::vector<JointResult> full;
  const HeldOutGain g = heldOutGainsBesideTerm({named}, path, full, true).front();
  const double p = g.finite ? heldoutPValue(g.gain, g.se) : 1.0;
  CandidateResult& r = out.candidates[named];
  const std::string key = std::string("heldout_gain_beside_") + toString(candidates_[path]);
  r.estimates[key] = g.gain;
  r.estimates[key + "_se"] = g.se;
  char buf[600];
  if (p < config_.alpha) {
    std::snprintf(buf, sizeof buf,
                  "; it holds beside %s, also significant (held-out gain over %s alone %+.4g +- "
                  "%.2g nats per reading, p %.2g)",
                  toString(candidates_[path]), toString(candidates_[path]), g.gain, g.se, p);
    out.decision += buf;
    return;
  }
  std::snprintf(buf, sizeof buf,
                "%s had the largest held-out gain (%+.4g nats per reading) but does not hold "
                "beside %s (%+.4g +- %.2g over %s "
                "alone, p %.2g): its gain was the path's misfit, in the readings that move most "
                "with the pose; %s named "
                "(held-out gain %+.4g, its evidence in the odometry steps)",
                toString(r.effect), r.heldout_gain_nats_per_point, toString(candidates_[path]),
                g.gain, g.se, toString(candidates_[path]), p, toString(candidates_[path]),
                out.candidates[path].heldout_gain_nats_per_point);
  out.decision = buf;
  out.primary_cause = toString(candidates_[path]);
}

/// Rule grid_first's fine grid: the refinement fits the geometry by least squares with the
/// rounding's variance q^2/12 beside the noise's (Sheppard's correction), the maximum-likelihood
/// fit of the rounded readings only while the grid is finer than about twice the noise; beyond,
/// the likelihood ratio beside the grid is not chi-squared (docs/results/hidden-effects.md,
/// Readings on a grid). Beside the t the geometry is the t's own fit: the ratio counts there.
bool SequenceDiagnosis::ratioCountsBeside(std::size_t under, bool grid) const {
  bool ratio_counts = !grid;
  if (grid) {
    std::vector<double> s;
    for (const auto& x : evaluateJoint(obs_, candidate_fits_[under], candidate_cfgs_[under]))
      s.push_back(x.sigma_m);
    std::sort(s.begin(), s.end());
    ratio_counts = !s.empty() && candidate_fits_[under].effects.range_grid_m <=
                                     rules::kFineGridOverNoise * s[s.size() / 10];
  }
  return ratio_counts;
}

/// Rules grid_first and tails_first: a reading grid is the format of the output, which biases
/// nothing, and heavy tails are a symptom. When either is named, each other significant physical
/// effect is fitted beside it (heldOutGainsBesideTerm); the largest whose held-out gain over the
/// symptom's term alone stays significant (one-sided, Bonferroni over those tried; on a fine grid
/// or beside the t the in-sample ratio counts too) is named, the symptom remaining beside it. With
/// none the symptom stays named (docs/results/hidden-effects.md, Heavy tails are a symptom, not a
/// cause; Readings on a grid).
void SequenceDiagnosis::nameCauseBesideSymptom(DiagnosisResult& out, Effect symptom) const {
  const bool grid = symptom == Effect::quantisation;
  const char* key = grid ? "heldout_gain_beside_grid" : "heldout_gain_beside_tails";
  const std::string key_se = std::string(key) + "_se";
  std::size_t under = candidates_.size();
  std::vector<std::size_t> physical;
  for (std::size_t c = 0; c < out.candidates.size(); ++c) {
    const CandidateResult& r = out.candidates[c];
    if (r.effect == symptom)
      under = c;
    else if (r.significant && r.identifiable && r.effect != Effect::quantisation)
      physical.push_back(c);
  }
  if (under == candidates_.size()) return;
  const bool ratio_counts = ratioCountsBeside(under, grid);
  std::size_t best = candidates_.size();
  double best_gain = 0.0;
  std::vector<JointResult> full;  // the fits beside the grid on all the data (stop and go)
  const std::vector<HeldOutGain> gains = heldOutGainsBesideTerm(physical, under, full);
  for (std::size_t k = 0; k < physical.size(); ++k) {
    const std::size_t c = physical[k];
    const HeldOutGain& g = gains[k];
    CandidateResult& r = out.candidates[c];
    r.estimates[key] = g.gain;
    r.estimates[key_se] = g.se;
    double p = g.finite ? heldoutPValue(g.gain, g.se) : 1.0;
    // Beside a fine grid or the t the likelihood ratio counts too (Bonferroni with the held-out
    // gain, as in the candidate's own p), when the held-out gain is positive.
    if (ratio_counts && g.finite && g.gain > 0.0 && !noiseShapeEffect(r.effect)) {
      const double p_lr = likelihoodRatioPBesideTerm(full[k], under);
      if (std::isfinite(p_lr))
        r.estimates[grid ? "p_likelihood_ratio_beside_grid" : "p_likelihood_ratio_beside_tails"] =
            p_lr;
      p = combinedPValue(p, kNaN, p_lr);
    }
    if (!(p * static_cast<double>(physical.size()) < config_.alpha)) continue;
    if (best == candidates_.size() || g.gain > best_gain) {
      best = c;
      best_gain = g.gain;
    }
  }
  describeCauseBesideSymptom(out, grid, under, physical.size(), best, best_gain);
}

/// The decision's words for nameCauseBesideSymptom (`best`: the candidate named, none when it is
/// candidates_.size()), and the cause it names.
void SequenceDiagnosis::describeCauseBesideSymptom(DiagnosisResult& out, bool grid,
                                                   std::size_t under, std::size_t tried,
                                                   std::size_t best, double best_gain) const {
  const std::string key_se =
      std::string(grid ? "heldout_gain_beside_grid" : "heldout_gain_beside_tails") + "_se";
  const double value = grid ? 1000.0 * candidate_fits_[under].effects.range_grid_m
                            : candidate_fits_[under].effects.student_dof;
  char buf[520];
  if (best == candidates_.size()) {
    std::snprintf(buf, sizeof buf,
                  grid ? "; the readings' grid (%.3g mm) is significant and no other effect holds "
                         "beside it (%zu tried, held-out "
                         "gain over the rounded model alone)"
                       : "; the tails (Student t, nu %.3g) are significant and no physical effect "
                         "holds beside them (%zu tried, "
                         "held-out gain over the t alone): cause unknown",
                  value, tried);
    out.decision += buf;
    return;
  }
  const CandidateResult& r = out.candidates[best];
  std::snprintf(
      buf, sizeof buf,
      grid
          ? "the readings' grid (%.3g mm) comes first, a format of the output that biases nothing; "
            "%s holds beside it "
            "(held-out gain over the rounded model alone +%.4g +- %.2g nats per reading; alone "
            "+%.4g): named, the "
            "rounding remains beside it"
          : "heavy tails (Student t, nu %.3g) come first, a symptom; %s holds beside them "
            "(held-out gain over the t "
            "alone +%.4g +- %.2g nats per reading; alone +%.4g): named, the tails remain beside it",
      value, toString(r.effect), best_gain, r.estimates.at(key_se), r.heldout_gain_nats_per_point);
  out.decision = buf;
  const auto lr =
      r.estimates.find(grid ? "p_likelihood_ratio_beside_grid" : "p_likelihood_ratio_beside_tails");
  if (lr != r.estimates.end()) {
    std::snprintf(buf, sizeof buf, "; in sample, the likelihood ratio beside it has p %.2g",
                  lr->second);
    out.decision += buf;
  }
  out.primary_cause = toString(r.effect);
}

/// Held-out gains of the effects of candidates `effects` beside the term of candidate `under` (the
/// Student t, the reading grid, a path term): the joint refinement with both terms against the one
/// with `under`'s alone (fitted once per fold for all of them), on the same scan folds (per-scan
/// blocks; stop and go, the odometry too). `full` receives the fits with both terms on all the data
/// (stop and go). from_under: both terms fitted from `under`'s solution (a path term's: its
/// headings hold the offset), a restricted shape at its estimate under `under`'s fold fit
/// (withCorrectedShape).
std::vector<HeldOutGain> SequenceDiagnosis::heldOutGainsBesideTerm(
    const std::vector<std::size_t>& effects, std::size_t under, std::vector<JointResult>& full,
    bool from_under) const {
  full.clear();
  full.resize(effects.size());
  std::vector<JointConfig> both(effects.size());
  std::vector<JointInit> start(effects.size());
  for (std::size_t k = 0; k < effects.size(); ++k)
    std::tie(both[k], start[k]) = from_under ? configWithBothTerms(under, effects[k])
                                             : configWithBothTerms(effects[k], under);
  const std::vector<int> fold = foldOfEachSighting(obs_, config_.folds);
  std::vector<HeldOut> held(effects.size(), HeldOut(1));
  for (int f = 0; f < config_.folds; ++f) {
    const auto split = foldSplit(obs_, fold, f);
    if (!split) continue;
    const auto& [tr, recorded] = *split;
    const JointResult ft =
        refineJoint(tr, initFrom(candidate_fits_[under]), warmStartConfig(candidate_cfgs_[under]));
    if (!ft.ok()) continue;
    const LandmarkObservations spread = dequantisedTestFold(fold, f);
    std::vector<std::size_t> scan;
    const auto lt = heldOutLikelihoods(tr, scoredReadings(candidate_cfgs_[under], recorded, spread),
                                       ft, candidate_cfgs_[under], &scan);
    for (std::size_t k = 0; k < effects.size(); ++k) {
      JointResult fb = refineJoint(tr, start[k], warmStartConfig(both[k]));
      if (from_under)
        fb = withCorrectedShape(tr, candidates_[effects[k]], ft, candidate_cfgs_[under],
                                std::move(fb), both[k]);
      if (!fb.ok()) continue;
      const auto lb =
          heldOutLikelihoods(tr, scoredReadings(both[k], recorded, spread), fb, both[k]);
      if (lt.size() != lb.size()) continue;
      for (std::size_t i = 0; i < lt.size(); ++i) {
        held[k].base.push_back(lt[i]);
        held[k].cand[0].push_back(lb[i]);
        held[k].block.push_back(scan[i]);
      }
    }
  }
  // Stop and go: the odometry held out too, leave one stop out, as in the candidates' gains
  // (odometryLikelihoods). Not under the motion prior, where a candidate's held-out steps are
  // scored against its paired baseline (paired_baselines_), which the fits beside a term do not
  // have.
  if (!baseline_fit_.motion_prior) {
    const auto ou = odometryHeldOut(obs_, candidate_fits_[under], candidate_cfgs_[under]);
    for (std::size_t k = 0; k < effects.size(); ++k) {
      if (held[k].base.empty()) continue;
      full[k] = refineJoint(obs_, start[k], both[k]);
      if (!full[k].ok()) continue;
      const auto ok = odometryHeldOut(obs_, full[k], both[k]);
      for (std::size_t j = 0; j < ou.size() && j < ok.size(); ++j)
        for (int twice = 0; twice < 2; ++twice) {  // one block per stop, two observations (x, y)
          held[k].base.push_back(0.5 * ou[j]);
          held[k].cand[0].push_back(0.5 * ok[j]);
          held[k].block.push_back(std::numeric_limits<std::size_t>::max() - j);
        }
    }
  }
  std::vector<HeldOutGain> out;
  for (auto& h : held) {
    h.points = static_cast<double>(h.base.size());
    out.push_back(h.base.empty() ? HeldOutGain{0.0, 0.0, false} : heldOutGain(h, 0));
  }
  return out;
}

/// Candidate c's refinement with candidate `under`'s term switched on too, and its start (c's
/// solution, with the t's degrees of freedom when `under` is the Student-t noise).
std::pair<JointConfig, JointInit> SequenceDiagnosis::configWithBothTerms(std::size_t c,
                                                                         std::size_t under) const {
  std::pair<JointConfig, JointInit> out{candidate_cfgs_[c], initFrom(candidate_fits_[c])};
  out.first.effects.enable(candidates_[under]);
  if (candidates_[under] == Effect::heavy_tails)
    out.second.effects.student_dof = candidate_fits_[under].effects.student_dof;
  return out;
}

/// In-sample evidence beside a fine reading grid or the Student t (nameCauseBesideSymptom), as the
/// candidates have it (stop and go; otherwise NaN): the likelihood ratio of `both`, a candidate's
/// fit with the grid (the t) on all the data, against the rounded model (the t) alone, chi-squared
/// for one parameter. Both model the recorded readings, so their likelihoods compare; an angle
/// offset shows in sample, the poles turning with the bearings take most of it out of sample
/// (docs/results/hidden-effects.md, Readings on a grid).
double SequenceDiagnosis::likelihoodRatioPBesideTerm(const JointResult& both,
                                                     std::size_t under) const {
  if (baseline_fit_.motion_prior || !both.ok()) return kNaN;
  return likelihoodRatioPValue(
      2.0 * (totalNegLogLikelihood(candidate_fits_[under]) - totalNegLogLikelihood(both)),
      both.effect_parameters - candidate_fits_[under].effect_parameters);
}

}  // namespace lidarcal::diagnosis::sequence
