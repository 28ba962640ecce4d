// SPDX-License-Identifier: BSD-3-Clause
// Step 3 for the tails of a static recording (diagnosis/tails.hpp): the tail models fitted on
// the scan folds, their held-out gains, each covariate's unique share, the full model on all the
// data (which beams carry the tails) and the effects fitted beside a pooled contamination.

#include <algorithm>
#include <cmath>
#include <string>

#include "diagnosis/static_scene/problem.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::static_scene {

/// The tail study's beams, covariates and specs (only when heavy_tails is a candidate).
void StaticDiagnosis::startTails() {
  tail_study_on_ =
      std::find(candidates_.begin(), candidates_.end(), Effect::heavy_tails) != candidates_.end();
  if (!tail_study_on_) return;
  tail_study_.beams = tailBeams(binned_, bin_fits_);
  tail_study_.available = tailAvailable(binned_, tail_study_.beams, edge_bins_);
  std::size_t inc_known = 0;
  for (const auto& b : binned_.bins) inc_known += b.inc_known;
  setupTailSpecs(tail_study_, inc_known >= 3, edge_bins_ >= 3, darknessVaries(binned_));
  tail_study_.floor_w = config_.outlier_floor;
  tail_study_.floor_density = binned_.window_max > binned_.window_min
                                  ? 1.0 / (binned_.window_max - binned_.window_min)
                                  : 0.0;
}

/// Fold k's readings under every tail model fitted on the other scans (the same folds, the same
/// held-out readings in the same order as the Gaussian baseline's).
void StaticDiagnosis::tailFold(int k, const std::vector<int>& fold) {
  std::vector<bool> train(data_.scans);
  for (std::size_t t = 0; t < data_.scans; ++t) train[t] = fold[t] != k;
  const std::vector<BinFit> fits = fitBins(binned_, train, 0.0);
  const auto fit_on = tailResiduals(binned_, fits, train, false, nullptr);
  const auto test = tailResiduals(*scored_readings_, fits, train, true, &tail_study_.block);
  // Warm starts: the full model from the pooled one, each model without a covariate from the
  // full one, the robust effects from the pooled one.
  std::vector<TailModel> models;
  for (std::size_t s = 0; s < tail_study_.specs.size(); ++s) {
    const TailModel* start_from = s == 0                        ? nullptr
                                  : tail_study_.dropped[s] >= 0 ? &models[1]
                                                                : &models[0];
    models.push_back(fitTailModel(tail_study_.beams, fit_on, tail_study_.specs[s],
                                  baseline_model_.sigma_e, tail_study_.floor_w,
                                  tail_study_.floor_density, 60, start_from));
    for (const auto& r : test)
      tail_study_.ll[s].push_back(models[s].logDensity(tail_study_.beams[r.beam], r.residual_m,
                                                       r.inflation, tail_study_.floor_w,
                                                       tail_study_.floor_density));
  }
}

/// Step 3 for the tails: held-out gains (pooled over the Gaussian baseline, covariates over the
/// pooled model, each covariate's unique part), the full model on all the data, the robust effects.
void StaticDiagnosis::afterCandidates(DiagnosisResult& out) {
  TailAttribution& ta = out.tails;
  if (!tail_study_on_) {
    ta.note = "heavy_tails is not among the candidates";
    return;
  }
  if (tail_study_.gauss.empty() || tail_study_.ll[0].size() != tail_study_.gauss.size()) {
    ta.note = "no held-out reading for the tail models";
    return;
  }
  ta.fitted = true;
  const HeldOutGain pooled = gainOf(tail_study_.ll[0], tail_study_.gauss, tail_study_.block);
  const HeldOutGain explained = gainOf(tail_study_.ll[1], tail_study_.ll[0], tail_study_.block);
  ta.pooled_gain_nats_per_point = pooled.gain;
  ta.pooled_gain_se = pooled.se;
  ta.explained_gain_nats_per_point = explained.gain;
  ta.explained_gain_se = explained.se;
  const HeldOutGain total = gainOf(tail_study_.ll[1], tail_study_.gauss, tail_study_.block);
  ta.p_value = total.finite ? heldoutPValue(total.gain, total.se) : 1.0;
  tailCovariateGains(ta);
  const auto all = tailResiduals(binned_, bin_fits_, {}, false, nullptr);
  const TailModel pooled_all = tailFullData(ta, all);
  tailRobust(out, all, pooled_all);
}

/// Each covariate's unique held-out gain (the full model over the model without it), Holm across
/// them; the cause is the effect of the one with the largest significant gain.
void StaticDiagnosis::tailCovariateGains(TailAttribution& ta) const {
  std::vector<double> p;
  for (std::size_t s = 0; s < tail_study_.specs.size(); ++s) {
    const int j = tail_study_.dropped[s];
    if (j < 0) continue;
    TailCovariateResult c;
    c.covariate = tailCovariateName(j);
    c.effect = tailCovariateEffect(j);
    const HeldOutGain g = gainOf(tail_study_.ll[1], tail_study_.ll[s], tail_study_.block);
    c.unique_gain_nats_per_point = g.gain;
    c.unique_gain_se = g.se;
    c.p_value = g.finite ? heldoutPValue(g.gain, g.se) : kNaN;
    c.share =
        ta.explained_gain_nats_per_point > 0.0 ? g.gain / ta.explained_gain_nats_per_point : 0.0;
    p.push_back(c.p_value);
    ta.covariates.push_back(c);
  }
  const auto adj = holmAdjust(p);
  const TailCovariateResult* top = nullptr;
  for (std::size_t k = 0; k < ta.covariates.size(); ++k) {
    TailCovariateResult& c = ta.covariates[k];
    c.p_holm = adj[k];
    c.significant =
        std::isfinite(adj[k]) && adj[k] < config_.alpha && c.unique_gain_nats_per_point > 0.0;
    if (c.significant && (!top || c.unique_gain_nats_per_point > top->unique_gain_nats_per_point))
      top = &c;
  }
  ta.cause = top ? toString(top->effect) : cause::kUnknown;
}

/// The pooled and the full tail models on all the data: parameters, and which beams carry the
/// tails. Returns the pooled model (the robust effects start from it).
TailModel StaticDiagnosis::tailFullData(TailAttribution& ta,
                                        const std::vector<TailReading>& all) const {
  const double fw = tail_study_.floor_w, fd = tail_study_.floor_density;
  const TailModel pooled =
      fitTailModel(tail_study_.beams, all, tail_study_.specs[0], baseline_model_.sigma_e, fw, fd);
  ta.pooled_fraction = pooled.tailProbability(TailBeam{});
  ta.pooled_wide_scale = pooled.wide;
  const TailModel full = fitTailModel(tail_study_.beams, all, tail_study_.specs[1],
                                      baseline_model_.sigma_e, fw, fd, 60, &pooled);
  ta.model["sigma_e"] = full.sigma_e;
  ta.model["wide_scale"] = full.wide;
  ta.model["wide_range_exponent"] = full.wide_exponent;
  ta.model["reference_range_m"] = std::exp(full.ref_log_range);
  ta.model["logit_intercept"] = full.beta[0];
  ta.model["em_iterations"] = full.iterations;
  ta.model["em_converged"] = full.converged ? 1.0 : 0.0;
  for (auto& c : ta.covariates) {
    int j = 0;
    while (c.covariate != tailCovariateName(j)) ++j;
    c.coefficient = full.beta[static_cast<std::size_t>(1 + j)];
    ta.model["logit_" + c.covariate] = c.coefficient;
  }
  tailClasses(ta, full, all);
  return pooled;
}

/// Tail readings (posterior sums) by class of beam, and the beams with the largest tail fraction.
void StaticDiagnosis::tailClasses(TailAttribution& ta, const TailModel& full,
                                  const std::vector<TailReading>& all) const {
  std::vector<double> tail(binned_.bins.size(), 0.0), n(binned_.bins.size(), 0.0);
  for (const auto& r : all) {
    tail[r.beam] += full.responsibility(tail_study_.beams[r.beam], r.residual_m, r.inflation,
                                        tail_study_.floor_w, tail_study_.floor_density);
    n[r.beam] += 1.0;
  }
  for (const char* cls : {"edge", "grazing", "range", "dark", "unknown"}) {
    ta.tail_readings_by_class[cls] = 0.0;
    ta.readings_by_class[cls] = 0.0;
  }
  std::vector<TailBeamReport> beams;
  for (std::size_t b = 0; b < binned_.bins.size(); ++b) {
    if (n[b] == 0.0) continue;
    const std::string cls = tailClass(full, tail_study_.beams[b], ta.covariates);
    ta.tail_readings += tail[b];
    ta.tail_readings_by_class[cls] += tail[b];
    ta.readings_by_class[cls] += n[b];
    TailBeamReport r;
    const Bin& bin = binned_.bins[b];
    r.bearing_rad = bin.angle;
    r.range_m = bin_fits_[b].m;
    r.incidence_rad = bin.inc_known ? std::acos(std::clamp(bin.cos_inc, 0.0, 1.0)) : kNaN;
    r.intensity = bin.intensity;
    r.edge = bin.edge;
    r.readings = static_cast<std::size_t>(n[b]);
    r.tail_fraction = tail[b] / n[b];
    r.tail_probability = full.tailProbability(tail_study_.beams[b]);
    r.cls = cls;
    beams.push_back(r);
  }
  std::stable_sort(beams.begin(), beams.end(),
                   [](const TailBeamReport& a, const TailBeamReport& b) {
                     return a.tail_fraction > b.tail_fraction;
                   });
  if (beams.size() > 10) beams.resize(10);
  ta.top_beams = std::move(beams);
}

/// Incidence exponent, range exponent, mixed-pixel fraction and dark-surface exponent fitted under
/// the pooled contamination (the tails do not drag them), with their held-out gains over the pooled
/// model.
void StaticDiagnosis::tailRobust(DiagnosisResult& out, const std::vector<TailReading>& all,
                                 const TailModel& pooled) {
  struct Item {
    std::size_t spec;
    Effect effect;
    const char* key;
  };
  const Item items[] = {{tail_study_.gamma, Effect::incidence_noise, "incidence_noise_exponent"},
                        {tail_study_.kappa, Effect::range_noise_law, "noise_exponent"},
                        {tail_study_.mixed, Effect::mixed_pixels, "mixed_pixel_fraction"},
                        {tail_study_.delta, Effect::dark_surface, "dark_noise_exponent"}};
  for (const Item& it : items) {
    if (it.spec == 0) continue;
    const TailModel m =
        fitTailModel(tail_study_.beams, all, tail_study_.specs[it.spec], baseline_model_.sigma_e,
                     tail_study_.floor_w, tail_study_.floor_density, 60, &pooled);
    const double value = it.spec == tail_study_.gamma   ? m.gamma
                         : it.spec == tail_study_.kappa ? m.kappa
                         : it.spec == tail_study_.delta ? m.delta
                                                        : m.mixed;
    const HeldOutGain g = gainOf(tail_study_.ll[it.spec], tail_study_.ll[0], tail_study_.block);
    const std::string key = it.key;
    out.tails.robust[key] = value;
    out.tails.robust[key + "_gain"] = g.gain;
    out.tails.robust[key + "_gain_se"] = g.se;
    out.tails.robust[key + "_p"] = g.finite ? heldoutPValue(g.gain, g.se) : 1.0;
    robust_estimate_[it.effect] = value;
    robust_sigma_e_[it.effect] = m.sigma_e;
    for (auto& c : out.candidates)
      if (c.effect == it.effect) c.estimates[key + "_robust"] = value;
  }
}

}  // namespace lidarcal::diagnosis::static_scene
