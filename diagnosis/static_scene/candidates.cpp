// SPDX-License-Identifier: BSD-3-Clause
// Step 3 of a static diagnosis: every candidate's reading model fitted on the scan folds and on
// all the data, its held-out gain, delta AIC, applicability, identifiability and estimates.

#include <cmath>
#include <limits>
#include <string>

#include "diagnosis/rules.hpp"
#include "diagnosis/static_scene/problem.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::static_scene {

/// Held-out readings (folds by scan) and held-out wall bins (leave one out).
void StaticDiagnosis::heldOut(HeldOut& held) {
  std::vector<int> fold(data_.scans);
  for (std::size_t t = 0; t < data_.scans; ++t)
    fold[t] = static_cast<int>(t % static_cast<std::size_t>(config_.folds));
  for (const auto& e : candidates_) free_terms_.push_back(freeTermsOf(e));
  startTails();
  const auto folds = static_cast<std::size_t>(config_.folds);
  for (int k = 0; k < config_.folds; ++k) {
    reportProgress(config_, kHeldOutStage, static_cast<std::size_t>(k), folds);
    foldLikelihoods(k, fold, held);
    if (tail_study_on_) tailFold(k, fold);
  }
  reportProgress(config_, kHeldOutStage, folds, folds);
  held.points = static_cast<double>(held.base.size());
  // the readings' part (the wall bins come next); deliberate copy
  if (tail_study_on_) tail_study_.gauss = held.base;
  wallLikelihoods(held);
}

/// Readings of fold k's scans under the models fitted on the other scans (block: scan).
void StaticDiagnosis::foldLikelihoods(int k, const std::vector<int>& fold, HeldOut& held) const {
  const double floor_w = config_.outlier_floor;
  std::vector<bool> train(data_.scans);
  for (std::size_t t = 0; t < data_.scans; ++t) train[t] = fold[t] != k;
  std::vector<BinFit> fb;
  const ReadingModel mb = fitModel(binned_, train, FreeTerms{}, reading_grid_m_, fb);
  std::vector<std::vector<BinFit>> fc(candidates_.size());
  std::vector<ReadingModel> mc(candidates_.size());
  for (std::size_t c = 0; c < candidates_.size(); ++c)
    mc[c] = fitModel(binned_, train, free_terms_[c], reading_grid_m_, fc[c]);
  for (std::size_t i = 0; i < binned_.y.size(); ++i) {
    const int bi = binned_.bin_of[i];
    if (bi < 0 || train[static_cast<std::size_t>(binned_.t[i])] ||
        fb[static_cast<std::size_t>(bi)].n == 0)
      continue;
    const Bin& bin = binned_.bins[static_cast<std::size_t>(bi)];
    held.base.push_back(
        readingLL(mb, *scored_readings_, bin, fb[static_cast<std::size_t>(bi)], i, floor_w));
    held.block.push_back(static_cast<std::size_t>(binned_.t[i]));
    for (std::size_t c = 0; c < candidates_.size(); ++c)
      held.cand[c].push_back(fc[c][static_cast<std::size_t>(bi)].n > 0
                                 ? readingLL(mc[c], *scored_readings_, bin,
                                             fc[c][static_cast<std::size_t>(bi)], i, floor_w)
                                 : kNaN);
  }
}

/// Wall bins: the bin means given the wall model (baseline: alpha_0 and lines).
void StaticDiagnosis::wallLikelihoods(HeldOut& held) const {
  if (!walls_.ok) return;
  for (std::size_t k = 0; k < walls_.loo_ll.size(); ++k) {
    held.base.push_back(walls_.loo_ll[k]);
    held.block.push_back(std::numeric_limits<std::size_t>::max() - k);
    for (std::size_t c = 0; c < candidates_.size(); ++c)
      held.cand[c].push_back(free_terms_[c].wall_b && walls_with_bias_.ok
                                 ? walls_with_bias_.loo_ll[k]
                                 : walls_.loo_ll[k]);
  }
}

/// In-sample log-likelihood of a model fitted on all the data (for delta AIC).
double StaticDiagnosis::inSampleLogLikelihood(const FreeTerms& fl, ReadingModel* fitted) const {
  std::vector<BinFit> ff;
  const ReadingModel mm = fitModel(binned_, {}, fl, reading_grid_m_, ff);
  if (fitted) *fitted = mm;
  double s = 0.0;
  forEachFitted(binned_, ff, [&](std::size_t i, const Bin& b, const BinFit& bf) {
    s += readingLL(mm, *scored_readings_, b, bf, i, config_.outlier_floor);
  });
  return s;
}

void StaticDiagnosis::beforeCandidates(DiagnosisResult& out) {
  baseline_in_sample_ll_ = inSampleLogLikelihood(FreeTerms{}, nullptr);
  out.baseline_neg_log_likelihood = -baseline_in_sample_ll_;
  fit_on_all_.resize(candidates_.size());
}

CandidateResult StaticDiagnosis::candidate(std::size_t c, const HeldOut& held,
                                           const DiagnosisResult& out) {
  CandidateResult r;
  r.effect = candidates_[c];
  r.statistic = statisticOf(r.effect, DiagnoseMode::static_scene);
  if (notApplicable(r)) return r;
  setScore(r, out.battery);
  const HeldOutGain gain = heldOutGain(held, c);
  if (!gain.finite) {
    r.applicable = false;
    r.p_value = kNaN;
    r.note = "could not be fitted on every fold";
    return r;
  }
  setHeldOutGain(r, gain);
  // A reading grid is plain in the readings (the `quantisation` statistic), on real sensors as
  // much as in simulations; whether the rounding explains anything is the held-out gain's to say
  // (on the dequantised readings, where the rounded model is the true one when it is).
  r.p_value =
      r.effect == Effect::quantisation ? r.p_heldout : combinedPValue(r.p_heldout, r.score_p_value);
  r.parameters = free_terms_[c].parameters();
  double ll_in = inSampleLogLikelihood(free_terms_[c], &fit_on_all_[c]);
  if (free_terms_[c].wall_b && walls_with_bias_.ok && walls_.ok)
    // only the walls' part differs
    ll_in = baseline_in_sample_ll_ + (walls_with_bias_.in_ll - walls_.in_ll);
  r.delta_aic = 2.0 * r.parameters - 2.0 * (ll_in - baseline_in_sample_ll_);
  setIdentifiability(r);
  setEstimates(r, fit_on_all_[c]);
  return r;
}

/// Effects one pose cannot show, or that each wall line absorbs: no test.
bool StaticDiagnosis::notApplicable(CandidateResult& r) const {
  const Effect e = r.effect;
  if (e == Effect::heading_error || e == Effect::angle_offset || e == Effect::odometry_scale) {
    r.applicable = false;
    r.identifiable = false;
    r.p_value = r.p_holm = r.score_p_value = kNaN;
    r.note = "one pose: nothing about stops or headings can be seen";
    return true;
  }
  if (e == Effect::dark_surface && !darknessVaries(binned_)) {
    r.applicable = false;
    r.p_value = r.p_holm = r.score_p_value = kNaN;
    r.note =
        "no reading records a return intensity (or all record one value): record with the driver's "
        "intensities on "
        "(ROS LaserScan intensities, a PCD intensity field)";
    return true;
  }
  if (e == Effect::landmark_bias) {
    r.identifiable = false;
    r.applicable = true;
    r.p_value = r.p_holm = r.score_p_value = kNaN;
    r.information_ratio = 0.0;
    r.standard_error = kInf;
    r.note = "an offset of one surface moves its fitted wall line as a whole: each line absorbs it";
    return true;
  }
  return false;
}

/// Correlation over the beams (weighted by their readings) of darkness and ln range: a
/// time-of-flight sensor without intensity compensation returns weaker from farther, and the two
/// covariates then say the same.
double StaticDiagnosis::darkRangeCorrelation() const {
  double n = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (std::size_t k = 0; k < binned_.bins.size(); ++k) {
    if (bin_fits_[k].n == 0 || !std::isfinite(binned_.bins[k].intensity)) continue;
    const double w = static_cast<double>(binned_.bins[k].idx.size()), x = binned_.bins[k].dark,
                 y = std::log(std::max(bin_fits_[k].m, 1e-3));
    n += w;
    sx += w * x;
    sy += w * y;
    sxx += w * x * x;
    syy += w * y * y;
    sxy += w * x * y;
  }
  const double vx = sxx - sx * sx / std::max(n, 1.0), vy = syy - sy * sy / std::max(n, 1.0);
  return vx > 0.0 && vy > 0.0 ? (sxy - sx * sy / n) / std::sqrt(vx * vy) : 0.0;
}

void StaticDiagnosis::setIdentifiability(CandidateResult& r) const {
  const Effect e = r.effect;
  if (e == Effect::incidence_bias) {
    // Rule identifiable: below 1 cm, or the estimate clear of zero.
    r.standard_error = walls_with_bias_.ok ? walls_with_bias_.b_se : kInf;
    r.identifiable = alpha0_identified_ && walls_with_bias_.ok &&
                     r.standard_error < std::max(0.01, std::abs(walls_with_bias_.b) /
                                                           rules::kIdentifiableEstimateSe);
    if (!r.identifiable)
      r.note = alpha0_identified_
                   ? "bends the walls almost as a range offset does: give the offset "
                     "(--range-offset) from a reference distance"
                   : "too few straight walls, or walls seen over too narrow a range of incidence";
  } else if (e == Effect::incidence_noise || e == Effect::range_noise_law ||
             e == Effect::dark_surface) {
    // The exponent's standard error from the spread of its covariate over the bins (the score's
    // information for a log-linear variance: n var(g) / 2).
    double mm = 0.0, m2 = 0.0, n = 0.0;
    for (const auto& b : binned_.bins) {
      if (e == Effect::incidence_noise && !b.inc_known) continue;
      const double g =
          e == Effect::incidence_noise ? -std::log(b.cos_inc)
          : e == Effect::dark_surface
              ? b.dark
              : std::log(std::max(bin_fits_[static_cast<std::size_t>(&b - binned_.bins.data())].m,
                                  1e-3));
      mm += g;
      m2 += g * g;
      n += static_cast<double>(b.idx.size());
    }
    const double nbins = static_cast<double>(binned_.bins.size());
    const double var = nbins > 0 ? std::max(m2 / nbins - std::pow(mm / nbins, 2), 0.0) : 0.0;
    r.information_ratio = var / (m2 / std::max(nbins, 1.0) + 1e-4);
    r.standard_error = var > 0.0 ? 1.0 / std::sqrt(2.0 * n * var) : kInf;
    r.identifiable = r.standard_error < 0.5;
    if (!r.identifiable)
      r.note = e == Effect::incidence_noise ? "no spread of incidence angles"
               : e == Effect::dark_surface  ? "no spread of intensities"
                                            : "no spread of ranges";
    // Rule dark_follows_range.
    if (r.identifiable && e == Effect::dark_surface &&
        std::abs(darkRangeCorrelation()) > rules::kConfounded) {
      r.identifiable = false;
      r.note = "the intensity follows the range on this recording (correlation " +
               std::to_string(darkRangeCorrelation()) +
               "): a dark surface cannot be told from the range law; record surfaces of different "
               "reflectivity at the same "
               "distance";
    }
  } else if (e == Effect::range_drift && window_scans_ > 0) {
    r.identifiable = false;
    r.note =
        "each window of scans has its own time trend per beam (the sensor moved), which absorbs a "
        "drift";
  } else if (e == Effect::mixed_pixels) {
    r.identifiable = edge_bins_ >= 3;
    if (!r.identifiable) r.note = "fewer than 3 beams at depth discontinuities";
  }
}

void StaticDiagnosis::setEstimates(CandidateResult& r, const ReadingModel& fm) const {
  const Effect e = r.effect;
  if (e == Effect::incidence_noise) r.estimates["incidence_noise_exponent"] = fm.gamma;
  if (e == Effect::range_noise_law) r.estimates["noise_exponent"] = fm.kappa;
  if (e == Effect::dark_surface) {
    r.estimates["dark_noise_exponent"] = fm.delta;
    r.estimates["dark_reference_intensity"] = binned_.i_ref;
    r.estimates["darkness_range_correlation"] = darkRangeCorrelation();
  }
  if (e == Effect::range_drift) {
    r.estimates["range_drift_m_per_scan"] = fm.drift;
    r.estimates["range_drift_over_recording_m"] = fm.drift * static_cast<double>(data_.scans - 1);
  }
  if (e == Effect::mixed_pixels) r.estimates["mixed_pixel_fraction"] = fm.mixed;
  if (e == Effect::heavy_tails) r.estimates["student_dof"] = fm.dof;
  if (e == Effect::quantisation) {
    r.estimates["grid_m"] = fm.q;
    // sigma_e of sigma_e |m|^kappa before the rounding
    r.estimates["noise_scale_unrounded"] = fm.sigma_e;
  }
  if (e == Effect::incidence_bias) {
    r.estimates["incidence_bias_m"] = walls_with_bias_.b;
    r.estimates["alpha0_with_it_m"] = walls_with_bias_.alpha0;
  }
}

}  // namespace lidarcal::diagnosis::static_scene
