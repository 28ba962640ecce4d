// SPDX-License-Identifier: BSD-3-Clause
// Step 5 of a static diagnosis: the named effect's model, the scene keys that simulate it, and
// how close its simulation, refitted with the baseline, comes to the data.

#include <algorithm>
#include <cmath>

#include "common/rng.hpp"
#include "diagnosis/static_scene/problem.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::static_scene {

/// How close simulations come to the measured residuals: KS distance of z, per-bin variances.
Closeness StaticDiagnosis::closenessOf(const std::vector<ResidualRecord>& measured,
                                       const SimSample& sim) const {
  Closeness c;
  std::vector<double> mz;
  for (const auto& r : measured) mz.push_back(r.z);
  c.ks_distance = ksDistance(mz, sim.z);
  std::vector<double> logs;
  for (std::size_t k = 0; k < binned_.bins.size(); ++k) {
    if (bin_fits_[k].n == 0 || sim.var[k].empty() || !(bin_fits_[k].s2 > 0.0)) continue;
    double mv = 0.0;
    for (double v : sim.var[k]) mv += v / static_cast<double>(sim.var[k].size());
    if (!(mv > 0.0)) continue;
    logs.push_back(std::abs(std::log(bin_fits_[k].s2 / mv)));
  }
  c.groups = logs.size();
  c.variance_ratio_median_abs_log = logs.empty() ? 0.0 : upperMedian(logs);
  return c;
}

/// The named effect's model: its scene keys, and its simulation refitted with the baseline.
void StaticDiagnosis::extend(std::size_t c, DiagnosisResult& out) const {
  const ReadingModel& fm = fit_on_all_[c];
  RangeEffects fx;
  ReadingModel sim_model = baseline_model_;
  const Effect e = candidates_[c];
  if (e == Effect::incidence_noise) fx.incidence_noise_exponent = fm.gamma;
  if (named_by_tails_ && e == Effect::incidence_noise && robust_estimate_.count(e))
    fx.incidence_noise_exponent = robust_estimate_.at(e);
  if (e == Effect::range_drift) {
    fx.range_drift_m_per_scan = fm.drift;
    fx.range_drift_reference_scan = binned_.t_mean;  // the fit's drift is c (t - t_mean)
  }
  if (e == Effect::mixed_pixels) fx.mixed_pixel_fraction = fm.mixed;
  if (e == Effect::dark_surface) {
    fx.dark_noise_exponent =
        named_by_tails_ && robust_estimate_.count(e) ? robust_estimate_.at(e) : fm.delta;
    fx.dark_reference_intensity = binned_.i_ref;
  }
  if (e == Effect::heavy_tails) fx.noise_student_dof = std::max(fm.dof, 2.1);
  if (e == Effect::quantisation) fx.range_resolution_m = fm.q;
  if (e == Effect::range_noise_law)
    sim_model.kappa =
        named_by_tails_ && robust_estimate_.count(e) ? robust_estimate_.at(e) : fm.kappa;
  sim_model.sigma_e = fm.sigma_e;
  // Named from the tails: the core noise fitted beside the contamination (its wild readings are
  // not simulated: the simulator has no covariate-dependent contamination).
  if (named_by_tails_ && robust_sigma_e_.count(e)) sim_model.sigma_e = robust_sigma_e_.at(e);
  WallFit w_sim = walls_;
  if (e == Effect::incidence_bias && walls_with_bias_.ok) {
    w_sim = walls_with_bias_;
    fx.incidence_bias_m = walls_with_bias_.b;
  }
  const double a0 = w_sim.ok ? w_sim.alpha0 : 0.0;
  out.extended_bias_alpha = {a0, 1.0};
  setSceneKeys(out, a0, sim_model, fx);
  SimSample ext;
  ext.var.resize(binned_.bins.size());
  for (int b = 0; b < config_.closeness_replicas; ++b) {
    const BinnedReadings rep =
        simulateStatic(binned_, bin_fits_, w_sim, sim_model,
                       deriveSeed(config_.seed, 6000 + static_cast<std::uint64_t>(b)), fx);
    std::vector<BinFit> fr;
    const ReadingModel mr = fitModel(rep, {}, FreeTerms{}, 0.0, fr);
    const auto rec = residualRecordsOf(rep, fr, mr);
    ext.add(rec, fr);
    if (b == 0) out.simulated_extended = rec;
  }
  out.closeness_extended = closenessOf(out.measured, ext);
}

void StaticDiagnosis::setSceneKeys(DiagnosisResult& out, double a0, const ReadingModel& sim_model,
                                   const RangeEffects& fx) const {
  auto& keys = out.scene_keys;
  keys["sensor.bias_alpha[0]"] = a0;
  keys["sensor.bias_alpha[1]"] = 1.0;
  if (sim_model.kappa != 2.0) keys["sensor.noise.exponent (kind power)"] = sim_model.kappa;
  keys["sensor.noise.sigma_e"] = sim_model.sigma_e;
  if (fx.incidence_noise_exponent != 0.0)
    keys[info(Effect::incidence_noise).scene_key] = fx.incidence_noise_exponent;
  if (fx.incidence_bias_m != 0.0)
    keys[info(Effect::incidence_bias).scene_key] = fx.incidence_bias_m;
  if (fx.range_drift_m_per_scan != 0.0) {
    keys[info(Effect::range_drift).scene_key] = fx.range_drift_m_per_scan;
    keys["sensor.effects.range_drift_reference_scan"] = fx.range_drift_reference_scan;
  }
  if (fx.mixed_pixel_fraction != 0.0)
    keys[info(Effect::mixed_pixels).scene_key] = fx.mixed_pixel_fraction;
  if (fx.noise_student_dof != 0.0) keys[info(Effect::heavy_tails).scene_key] = fx.noise_student_dof;
  if (fx.range_resolution_m != 0.0)
    keys[info(Effect::quantisation).scene_key] = fx.range_resolution_m;
  if (fx.dark_noise_exponent != 0.0) {
    keys[info(Effect::dark_surface).scene_key] = fx.dark_noise_exponent;
    keys["sensor.effects.dark_reference_intensity"] = fx.dark_reference_intensity;
  }
}

}  // namespace lidarcal::diagnosis::static_scene
