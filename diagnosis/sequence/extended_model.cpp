// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/extended_model.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "calibration/evaluation.hpp"
#include "calibration/inversion.hpp"
#include "common/pose2.hpp"
#include "common/rng.hpp"
#include "common/stats_util.hpp"
#include "diagnosis/sequence/problem.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::sequence {
namespace {

/// Group of a residual for the variance ratios: landmark x stop x edge.
long groupKey(const JointReading& r) {
  return (static_cast<long>(r.landmark) * 100000 + static_cast<long>(r.stop)) * 2 +
         (r.edge ? 1 : 0);
}

}  // namespace

void appendStandardised(ZSample& sample, const std::vector<ReadingRow>& rs) {
  for (const auto& r : rs) {
    sample.z.push_back(r.z);
    sample.group.push_back(groupKey(r.r));
  }
}

Closeness closeness(const ZSample& measured, const ZSample& simulated) {
  Closeness c;
  c.ks_distance = ksDistance(measured.z, simulated.z);
  std::map<long, std::pair<std::vector<double>, std::vector<double>>> g;
  for (std::size_t i = 0; i < measured.z.size(); ++i)
    g[measured.group[i]].first.push_back(measured.z[i]);
  for (std::size_t i = 0; i < simulated.z.size(); ++i)
    g[simulated.group[i]].second.push_back(simulated.z[i]);
  auto var = [](const std::vector<double>& v) {
    double m = 0.0, s = 0.0;
    for (double x : v) m += x / static_cast<double>(v.size());
    for (double x : v) s += (x - m) * (x - m);
    return s / static_cast<double>(v.size() - 1);
  };
  std::vector<double> logs;
  for (const auto& [k, v] : g) {
    if (v.first.size() < 5 || v.second.size() < 5) continue;
    const double a = var(v.first), b = var(v.second);
    if (!(a > 0.0 && b > 0.0)) continue;
    logs.push_back(std::abs(std::log(a / b)));
  }
  c.groups = logs.size();
  if (!logs.empty()) c.variance_ratio_median_abs_log = upperMedian(logs);
  return c;
}

std::vector<ResidualRecord> residualRecords(const std::vector<ReadingRow>& rs) {
  std::vector<ResidualRecord> out;
  out.reserve(rs.size());
  for (const auto& w : rs) {
    ResidualRecord r;
    r.range_m = w.r.d_m;
    r.incidence_rad = std::acos(std::clamp(w.r.cos_incidence, 0.0, 1.0));
    r.lateral = w.r.lateral;
    r.group = w.r.landmark;
    r.time = static_cast<double>(w.r.scan);
    r.bearing_rad = w.r.angle_rad;
    r.stop = static_cast<int>(w.r.stop);
    r.edge = w.r.edge;
    r.residual_m = w.r.y_m - w.r.mean_m;
    r.z = w.z;
    out.push_back(r);
  }
  return out;
}

double calibrationMseRatio(const LandmarkObservations& obs, const JointResult& fit,
                           const JointConfig& cfg, const std::vector<std::vector<double>>& truth) {
  RangeModel m = fit.model;
  m.range_min_m = obs.range_min_m;
  m.range_max_m = fit.window_max_m;
  std::optional<RangeInverter> inv;
  try {
    inv.emplace(m, inversionWindow(m, InversionMethod::ls));
  } catch (const std::invalid_argument&) {
    return kNaN;
  }
  const auto rd = evaluateJoint(obs, fit, cfg);
  std::vector<double> t, raw, cor;
  std::size_t k = 0;
  for (std::size_t si = 0; si < obs.sightings.size(); ++si) {
    const auto& s = obs.sightings[si];
    for (std::size_t j = 0; j < s.beams.size(); ++j) {
      if (!std::isfinite(s.beams[j].range_m)) continue;
      while (k < rd.size() && rd[k].sighting < si) ++k;
      if (k >= rd.size() || rd[k].sighting != si || si >= truth.size() || j >= truth[si].size())
        continue;
      const JointReading& r = rd[k++];
      const double terms = r.mean_m - fit.model.bias(r.d_m);
      const auto d = inv->invert(r.y_m - terms);
      t.push_back(truth[si][j]);
      raw.push_back(r.y_m);
      cor.push_back(d ? *d : kNaN);
    }
  }
  return compareRanges(t, raw, cor).mse_ratio;
}

double effectSize(Effect e, const JointResult& f) {
  const auto& x = f.effects;
  if (e == Effect::landmark_bias) {
    double s = 0.0;
    for (const auto& [id, o] : x.landmark_offset_m) s += o * o;
    return x.landmark_offset_m.empty()
               ? 0.0
               : std::sqrt(s / static_cast<double>(x.landmark_offset_m.size()));
  }
  if (e == Effect::heading_error) return x.heading_rms_rad;
  if (e == Effect::range_drift) return std::abs(x.drift_m_per_scan);
  if (e == Effect::angle_offset) return std::abs(x.angle_offset_rad);
  if (e == Effect::incidence_bias) return std::abs(x.incidence_bias_m);
  if (e == Effect::odometry_scale) return std::abs(x.odometry_scale);
  if (e == Effect::incidence_noise) return std::abs(x.incidence_noise_exponent);
  if (e == Effect::dark_surface) return std::abs(x.dark_noise_exponent);
  if (e == Effect::range_noise_law) return std::abs(x.noise_exponent - 2.0);
  if (e == Effect::heavy_tails) return x.student_dof > 2.0 ? 1.0 / x.student_dof : 0.0;
  return 0.0;
}

std::map<std::string, double> effectEstimates(Effect e, const JointResult& f) {
  const auto& x = f.effects;
  std::map<std::string, double> m;
  if (e == Effect::incidence_noise) m["incidence_noise_exponent"] = x.incidence_noise_exponent;
  if (e == Effect::dark_surface) {
    m["dark_noise_exponent"] = x.dark_noise_exponent;
    m["dark_reference_intensity"] = x.dark_reference_intensity;
  }
  if (e == Effect::incidence_bias) m["incidence_bias_m"] = x.incidence_bias_m;
  if (e == Effect::landmark_bias) {
    double s = 0.0;
    for (const auto& [id, o] : x.landmark_offset_m) {
      m["landmark_offset_m[" + std::to_string(id) + "]"] = o;
      s += o * o;
    }
    m["landmark_offset_rms_m"] =
        x.landmark_offset_m.empty()
            ? 0.0
            : std::sqrt(s / static_cast<double>(x.landmark_offset_m.size()));
  }
  if (e == Effect::heading_error) m["heading_rms_deg"] = rad2deg(x.heading_rms_rad);
  if (e == Effect::range_drift) m["range_drift_m_per_scan"] = x.drift_m_per_scan;
  if (e == Effect::mixed_pixels) m["mixed_pixel_fraction"] = x.mixed_pixel_fraction;
  if (e == Effect::angle_offset) m["angle_offset_deg"] = rad2deg(x.angle_offset_rad);
  if (e == Effect::range_noise_law) m["noise_exponent"] = x.noise_exponent;
  if (e == Effect::odometry_scale) m["odometry_scale"] = x.odometry_scale;
  if (e == Effect::heavy_tails) m["student_dof"] = x.student_dof;
  if (e == Effect::quantisation) {
    m["grid_m"] = x.range_grid_m;
    m["noise_scale_unrounded"] = f.model.noise.sigma_e;  // sigma_e of the law before the rounding
  }
  return m;
}

std::map<std::string, double> sceneKeys(Effect e, const JointResult& f, const ReplicaPlan& plan) {
  std::map<std::string, double> k;
  const auto& x = f.effects;
  const auto& c = plan.config;
  for (std::size_t i = 0; i < c.model.bias.alpha.size(); ++i)
    k["sensor.bias_alpha[" + std::to_string(i) + "]"] = c.model.bias.alpha[i];
  if (c.model.noise.kind == NoiseKind::power)
    k["sensor.noise.exponent (kind power)"] = c.model.noise.exponent;
  k["sensor.noise.sigma_e"] = c.model.noise.sigma_e;
  if (e == Effect::landmark_bias)
    for (std::size_t i = 0; i < plan.ids.size(); ++i)
      k["landmarks[" + std::to_string(i) + "].range_offset_m (id " + std::to_string(plan.ids[i]) +
        ")"] = c.landmarks[i].range_offset_m;
  const std::map<Effect, double> value = {{Effect::incidence_noise, x.incidence_noise_exponent},
                                          {Effect::incidence_bias, x.incidence_bias_m},
                                          {Effect::heading_error, rad2deg(x.heading_rms_rad)},
                                          {Effect::range_drift, x.drift_m_per_scan},
                                          {Effect::mixed_pixels, x.mixed_pixel_fraction},
                                          {Effect::angle_offset, rad2deg(x.angle_offset_rad)},
                                          {Effect::odometry_scale, x.odometry_scale},
                                          {Effect::heavy_tails, x.student_dof},
                                          {Effect::quantisation, x.range_grid_m},
                                          {Effect::dark_surface, x.dark_noise_exponent}};
  if (const auto it = value.find(e); it != value.end()) k[info(e).scene_key] = it->second;
  // The fit's drift is zero at its mean scan; the simulator's at the reference scan given here.
  if (e == Effect::range_drift)
    k["sensor.effects.range_drift_reference_scan"] = c.effects.range_drift_reference_scan;
  if (e == Effect::dark_surface) {
    k["sensor.effects.dark_reference_intensity"] = c.effects.dark_reference_intensity;
    for (std::size_t i = 0; i < plan.ids.size(); ++i)
      k["landmarks[" + std::to_string(i) + "].intensity (id " + std::to_string(plan.ids[i]) + ")"] =
          c.landmarks[i].intensity;
  }
  return k;
}

void SequenceDiagnosis::afterCandidates(DiagnosisResult& out) {
  if (truth_)
    out.calibration_mse_ratio_baseline =
        calibrationMseRatio(obs_, baseline_fit_, baseline_cfg_, *truth_);
}

/// The named effect's model: its scene keys, and its simulation refitted with the baseline.
void SequenceDiagnosis::extend(std::size_t c, DiagnosisResult& out) const {
  const JointResult& fc = candidate_fits_[c];
  out.extended_bias_alpha = fc.model.bias.alpha;
  out.calibration_mse_ratio_extended = out.candidates[c].calibration_mse_ratio;
  const ReplicaPlan plan = replicaPlan(obs_, fc, out.radius_known);
  out.scene_keys = sceneKeys(candidates_[c], fc, plan);
  ZSample sim_ext;
  for (int b = 0; b < config_.closeness_replicas; ++b) {
    const LandmarkObservations rep =
        simulateReplica(plan, obs_, poseNoise(fc, candidate_cfgs_[c]),
                        deriveSeed(config_.seed, 5000 + static_cast<std::uint64_t>(b)));
    const JointResult f = replicaFit(rep);
    if (!f.ok()) continue;
    const auto rr = readingRows(rep, f, baseline_cfg_);
    appendStandardised(sim_ext, rr);
    if (out.simulated_extended.empty()) out.simulated_extended = residualRecords(rr);
  }
  out.closeness_extended = closeness(measured_z_, sim_ext);
}

}  // namespace lidarcal::diagnosis::sequence
