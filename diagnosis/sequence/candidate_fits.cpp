// SPDX-License-Identifier: BSD-3-Clause
// Step 3 of a sequence diagnosis, the fits: each candidate on all the data, the baseline settled
// in the best optimum they find, and every model refitted on the folds for the held-out
// likelihoods of the readings and the odometry.

#include <cmath>
#include <limits>
#include <optional>

#include "common/stats_util.hpp"
#include "diagnosis/sequence/folds.hpp"
#include "diagnosis/sequence/held_out.hpp"
#include "diagnosis/sequence/noise_shape.hpp"
#include "diagnosis/sequence/problem.hpp"
#include "diagnosis/sequence/starts.hpp"

namespace lidarcal::diagnosis::sequence {

/// Fold f's held-out readings spread over their grid cells (nothing when the readings lie on no
/// grid): split once per fold, for every model scored on them (scored).
LandmarkObservations SequenceDiagnosis::dequantisedTestFold(const std::vector<int>& fold,
                                                            int f) const {
  return reading_grid_m_ > 0.0 ? foldSplit(dequantised_, fold, f)->second : LandmarkObservations{};
}

/// The held-out readings a model of `cfg` is scored on: as recorded for the rounded model or when
/// the readings lie on no grid, otherwise spread over their cells (`spread`, dequantisedTestFold).
const LandmarkObservations& SequenceDiagnosis::scoredReadings(
    const JointConfig& cfg, const LandmarkObservations& recorded,
    const LandmarkObservations& spread) const {
  return reading_grid_m_ > 0.0 && !cfg.effects.quantised ? spread : recorded;
}

/// The candidates' fits on all the data (candidate_cfgs_, candidate_fits_): from candidateStart
/// (measured_start: it turns the start by the measured statistics) or from the baseline's solution.
/// Progress: candidate c is step c of `steps` of `stage`.
void SequenceDiagnosis::fitCandidates(bool measured_start, const char* stage, std::size_t steps) {
  candidate_cfgs_.clear();
  candidate_fits_.clear();
  for (const auto& e : candidates_) {
    reportProgress(config_, stage, candidate_cfgs_.size(), steps);
    candidate_cfgs_.push_back(effectConfig(baseline_cfg_, e));
    // The neutral start matters for the terms that bend the geometry the baseline settled in.
    candidate_fits_.push_back(
        notFitted(e) ? baseline_fit_
                     : bestOf(measured_start ? candidateStart(e) : initFrom(baseline_fit_),
                              candidate_cfgs_.back(),
                              e == Effect::incidence_bias || e == Effect::landmark_bias));
  }
}

/// Under the motion prior two fits of one model can settle in different optima (settleBaseline).
/// The baseline is refitted from candidate c's solution fc; when fc fits worse than the better of
/// that refit and `base`, fc is refitted from it (the better of the two kept). Returns the refit
/// when it beats `base` (nothing: `base` is the baseline in fc's optimum).
std::optional<JointResult> SequenceDiagnosis::sameOptimum(const LandmarkObservations& obs,
                                                          std::size_t c, JointResult& fc,
                                                          const JointResult& base) const {
  std::optional<JointResult> back =
      refineJoint(obs, baselineStart(fc), warmStartConfig(baseline_cfg_));
  if (!(totalNegLogLikelihood(*back) < totalNegLogLikelihood(base))) back.reset();
  const JointResult& better = back ? *back : base;
  if (totalNegLogLikelihood(fc) > totalNegLogLikelihood(better)) {
    JointResult again =
        refineJoint(obs, driveStart(candidates_[c], better), warmStartConfig(candidate_cfgs_[c]));
    if (totalNegLogLikelihood(again) < totalNegLogLikelihood(fc)) fc = std::move(again);
  }
  return back;
}

/// A candidate's fit can find a better optimum of the baseline's own likelihood (a pose per scan
/// leaves many): the baseline is refitted from every candidate's solution that beats it by more
/// than 2 nats; the best refit that beats the baseline by more than 1 nat replaces it. True when
/// one did. Under the motion prior only: stop and go holds each heading where the start puts it, so
/// a refit from a heading_error fit's solution would keep that fit's headings
/// (docs/results/hidden-effects.md, Robots that never stop).
bool SequenceDiagnosis::settleBaseline() {
  if (!baseline_fit_.motion_prior) return false;
  JointResult best;
  for (std::size_t c = 0; c < candidates_.size(); ++c) {
    if (!candidate_fits_[c].ok() || notFitted(candidates_[c]) ||
        !(totalNegLogLikelihood(candidate_fits_[c]) < totalNegLogLikelihood(baseline_fit_) - 2.0))
      continue;
    JointResult back =
        refineJoint(obs_, baselineStart(candidate_fits_[c]), warmStartConfig(baseline_cfg_));
    if (totalNegLogLikelihood(back) <
        std::min(totalNegLogLikelihood(best), totalNegLogLikelihood(baseline_fit_) - 1.0))
      best = std::move(back);
  }
  if (!best.ok()) return false;
  baseline_fit_ = std::move(best);
  return true;
}

/// Held-out likelihoods: folds by scan, odometry by stop. The candidates are fitted here (stop
/// and go) or refitted: all of them against a settled baseline (settleBaseline), otherwise those
/// whose start needs the measured statistics (candidateStart).
void SequenceDiagnosis::heldOut(HeldOut& held) {
  const std::size_t fold_steps = static_cast<std::size_t>(config_.folds);
  std::size_t steps_before = 0;
  if (candidate_fits_.empty() || baseline_settled_) {
    steps_before = candidates_.size();
    fitCandidates(true, kHeldOutStage, steps_before + fold_steps);
  } else {
    for (std::size_t c = 0; c < candidates_.size(); ++c) {
      const Effect e = candidates_[c];
      if (e == Effect::angle_offset || e == Effect::odometry_scale)
        candidate_fits_[c] = bestOf(candidateStart(e), candidate_cfgs_[c], false);
    }
  }
  // The likelihood ratio compares the candidate with the baseline in the same optimum.
  baseline_nll_in_optimum_.assign(candidates_.size(), totalNegLogLikelihood(baseline_fit_));
  shape_lr_statistic_.assign(candidates_.size(), kNaN);
  for (std::size_t c = 0; c < candidates_.size() && baseline_fit_.motion_prior; ++c) {
    if (notFitted(candidates_[c]) || !candidate_fits_[c].ok()) continue;
    const auto back = sameOptimum(obs_, c, candidate_fits_[c], baseline_fit_);
    if (back) baseline_nll_in_optimum_[c] = totalNegLogLikelihood(*back);
    candidate_fits_[c] = withCorrectedShape(obs_, candidates_[c], back ? *back : baseline_fit_,
                                            baseline_cfg_, std::move(candidate_fits_[c]),
                                            candidate_cfgs_[c], &shape_lr_statistic_[c]);
  }
  // Under the motion prior each term of the geometry is paired with the baseline refitted from
  // its own solution, for the held-out steps (odometryLikelihoods).
  paired_baselines_.clear();
  paired_baselines_.resize(candidates_.size());
  for (std::size_t c = 0; c < candidates_.size() && baseline_fit_.motion_prior; ++c)
    if (geometryTerm(candidates_[c]) && !notFitted(candidates_[c]) && candidate_fits_[c].ok())
      paired_baselines_[c] =
          refineJoint(obs_, baselineStart(candidate_fits_[c]), warmStartConfig(baseline_cfg_));
  foldLikelihoods(held, steps_before, steps_before + fold_steps);
  odometryLikelihoods(held);
  held.points = static_cast<double>(held.base.size());
}

/// Readings of each fold's sightings under the models fitted on the other folds (block: scan).
void SequenceDiagnosis::foldLikelihoods(HeldOut& held, std::size_t steps_before,
                                        std::size_t steps) const {
  const std::vector<int> fold = foldOfEachSighting(obs_, config_.folds);
  for (int f = 0; f < config_.folds; ++f) {
    reportProgress(config_, kHeldOutStage, steps_before + static_cast<std::size_t>(f), steps);
    const auto split = foldSplit(obs_, fold, f);
    if (!split) continue;
    const auto& [tr, recorded] = *split;
    const LandmarkObservations spread = dequantisedTestFold(fold, f);
    const LandmarkObservations& te = scoredReadings(baseline_cfg_, recorded, spread);
    const JointResult fb = refineJoint(tr, initFrom(baseline_fit_), warmStartConfig(baseline_cfg_));
    if (!fb.ok()) continue;
    std::vector<std::size_t> scan;
    const auto eb = heldOutLikelihoods(tr, te, fb, baseline_cfg_, &scan);
    std::vector<std::vector<double>> ec(candidates_.size());
    bool ok = true;
    for (std::size_t c = 0; c < candidates_.size(); ++c) {
      if (notFitted(candidates_[c])) {
        ec[c] = eb;
        continue;
      }
      JointResult fc = refineJoint(
          tr, !candidate_fits_[c].ok() ? initFrom(baseline_fit_) : initFrom(candidate_fits_[c]),
          warmStartConfig(candidate_cfgs_[c]));
      if (!fc.ok()) {
        ok = false;
        break;
      }
      // Under the motion prior the candidate is scored against the baseline in its own optimum
      // (sameOptimum): that baseline's difference to fb's is taken off its readings (held.base
      // stays fb's).
      const std::optional<JointResult> bb =
          baseline_fit_.motion_prior ? sameOptimum(tr, c, fc, fb) : std::nullopt;
      fc = withCorrectedShape(tr, candidates_[c], bb ? *bb : fb, baseline_cfg_, std::move(fc),
                              candidate_cfgs_[c]);
      ec[c] = heldOutLikelihoods(tr, scoredReadings(candidate_cfgs_[c], recorded, spread), fc,
                                 candidate_cfgs_[c]);
      if (ec[c].size() != eb.size()) {
        ok = false;
        continue;
      }
      if (!bb) continue;
      const std::vector<double> ebb = heldOutLikelihoods(tr, te, *bb, baseline_cfg_);
      if (ebb.size() != eb.size()) {
        ok = false;
        continue;
      }
      for (std::size_t i = 0; i < eb.size(); ++i) ec[c][i] += eb[i] - ebb[i];
    }
    if (!ok) continue;
    for (std::size_t i = 0; i < eb.size(); ++i) {
      held.base.push_back(eb[i]);
      held.block.push_back(scan[i]);
      for (std::size_t c = 0; c < candidates_.size(); ++c) held.cand[c].push_back(ec[c][i]);
    }
  }
}

/// Odometry, leave one stop out (stop and go) or one step out (under the motion prior), from the
/// fits on all the data.
void SequenceDiagnosis::odometryLikelihoods(HeldOut& held) const {
  // Stop and go: a stop's commanded position against its own pose prior. Under the motion prior no
  // pose has a prior of its own: each odometry step between two located poses is held out
  // (stepHeldOut), three observations (x, y, heading) per step. The terms of the geometry predict
  // the steps their own way (an incidence bias straightens the path it distorts), each scored
  // against the baseline refitted from its own solution (paired_baselines_), since two optima of
  // one model differ on the steps by more than an effect does. The noise terms' steps differ from
  // the baseline's only through a second-order term of the linearised leave-one-out, unstable where
  // few readings locate a pose: they are given the baseline's.
  if (baseline_fit_.motion_prior) {
    const auto sb = stepHeldOut(obs_, baseline_fit_, baseline_cfg_);
    std::vector<std::vector<double>> sc(candidates_.size());
    for (std::size_t c = 0; c < candidates_.size(); ++c) {
      sc[c] = sb;
      if (!geometryTerm(candidates_[c]) || notFitted(candidates_[c])) continue;
      if (!candidate_fits_[c].ok() || !paired_baselines_[c].ok()) {
        sc[c].assign(sb.size(), kNaN);
        continue;
      }
      // The candidate's steps against its paired baseline's, added to the baseline's.
      const std::vector<double> own = stepHeldOut(obs_, candidate_fits_[c], candidate_cfgs_[c]),
                                pair = stepHeldOut(obs_, paired_baselines_[c], baseline_cfg_);
      for (std::size_t k = 0; k < sb.size() && own.size() == sb.size() && pair.size() == sb.size();
           ++k)
        sc[c][k] += own[k] - pair[k];
    }
    for (std::size_t k = 0; k < sb.size() && !held.base.empty(); ++k) {
      // poses the readings do not locate: left out for every model
      if (!std::isfinite(sb[k])) continue;
      const std::size_t key = std::numeric_limits<std::size_t>::max() - k;
      for (int thrice = 0; thrice < 3; ++thrice) {
        held.base.push_back(sb[k] / 3.0);
        held.block.push_back(key);
        for (std::size_t c = 0; c < candidates_.size(); ++c) held.cand[c].push_back(sc[c][k] / 3.0);
      }
    }
    return;
  }
  const auto ob = odometryHeldOut(obs_, baseline_fit_, baseline_cfg_);
  std::vector<std::vector<double>> oc(candidates_.size());
  for (std::size_t c = 0; c < candidates_.size(); ++c)
    oc[c] = !candidate_fits_[c].ok()
                ? std::vector<double>(ob.size(), kNaN)
                : odometryHeldOut(obs_, candidate_fits_[c], candidate_cfgs_[c]);
  for (std::size_t k = 0; k < ob.size() && !held.base.empty(); ++k) {
    // One block per stop, after the scans' blocks; two observations (x, y) per stop.
    const std::size_t key = std::numeric_limits<std::size_t>::max() - k;
    for (int twice = 0; twice < 2; ++twice) {
      held.base.push_back(0.5 * ob[k]);
      held.block.push_back(key);
      for (std::size_t c = 0; c < candidates_.size(); ++c) held.cand[c].push_back(0.5 * oc[c][k]);
    }
  }
}

}  // namespace lidarcal::diagnosis::sequence
