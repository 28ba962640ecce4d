// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/noise_shape.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>
#include <boost/math/tools/minima.hpp>

#include "common/range_effects.hpp"
#include "common/stats_util.hpp"
#include "diagnosis/sequence/pose_uncertainty.hpp"
#include "diagnosis/sequence/problem.hpp"

namespace lidarcal::diagnosis::sequence {

bool restrictedShape(Effect e) { return e == Effect::incidence_noise || e == Effect::dark_surface; }

void setNoiseShape(Effect e, double v, JointInit& init) {
  if (e == Effect::incidence_noise) init.effects.incidence_noise_exponent = v;
  if (e == Effect::dark_surface) init.effects.dark_noise_exponent = v;
}

double restrictedShapeEstimate(const LandmarkObservations& obs, const JointResult& fit,
                               const JointConfig& cfg, Effect e, double* statistic) {
  const std::vector<JointReading> rs = evaluateJoint(obs, fit, cfg);
  const std::vector<PoseInformation> info = poseInformation(obs, fit, cfg);
  // the odometry's (and the first pose's prior's) blocks
  const PoseChain odo = poseChainInformation({}, obs, fit, cfg, 1.0);
  const std::vector<Eigen::Matrix3d>&odo_a = odo.a, &odo_b = odo.b;
  const JointEffectEstimates& fx = fit.effects;
  auto shapes = [&](double v) {  // the noise law's shape h_i of every reading at exponent v
    const double gamma = e == Effect::incidence_noise ? v : fx.incidence_noise_exponent;
    const double delta = e == Effect::dark_surface ? v : fx.dark_noise_exponent;
    std::vector<double> h(rs.size());
    for (std::size_t i = 0; i < rs.size(); ++i)
      h[i] = std::max(fit.model.noise.stddev(rs[i].d_m, fit.model.bias) *
                          incidenceNoiseFactor(gamma, rs[i].cos_incidence) *
                          darkNoiseFactor(delta, rs[i].darkness),
                      1e-12);
    return h;
  };
  std::vector<bool> used(rs.size(), false);  // within 4 sigma, as the refinement's noise law
  std::size_t n_used = 0;
  for (std::size_t i = 0; i < rs.size() && i < info.size(); ++i)
    if (std::abs(rs[i].y_m - rs[i].mean_m) <= 4.0 * rs[i].sigma_m && rs[i].stop < odo_a.size()) {
      used[i] = true;
      ++n_used;
    }
  if (n_used < 10) return kNaN;
  auto negative = [&](double v) {  // minus the restricted log-likelihood, the scale profiled
    const std::vector<double> h = shapes(v);
    std::vector<Eigen::Matrix3d> reading_a(odo_a.size(), Eigen::Matrix3d::Zero());
    double sum_log_h = 0.0, sum_z2 = 0.0;
    for (std::size_t i = 0; i < rs.size() && i < info.size(); ++i) {
      if (!used[i]) continue;
      reading_a[rs[i].stop] += info[i].g * info[i].g.transpose() / (h[i] * h[i]);
      const double z = (rs[i].y_m - rs[i].mean_m) / h[i];
      sum_log_h += std::log(h[i]);
      sum_z2 += z * z;
    }
    const double m = static_cast<double>(n_used);
    auto at_scale = [&](double log_s) {
      const double s2 = std::exp(2.0 * log_s);
      std::vector<Eigen::Matrix3d> a = odo_a;
      for (std::size_t k = 0; k < a.size(); ++k) a[k] += reading_a[k] / s2;
      const double log_det = blockTridiagonalLogDet(a, odo_b);
      return m * log_s + sum_log_h + 0.5 * sum_z2 / s2 +
             0.5 * (std::isfinite(log_det) ? log_det : 1e300);
    };
    // the scale without the poses' share
    const double log_ml = 0.5 * std::log(std::max(sum_z2 / m, 1e-300));
    return boost::math::tools::brent_find_minima(at_scale, log_ml - 1.0, log_ml + 1.0, 30).second;
  };
  // The refinement's upper ends, but from 0: grazing beams and dark returns are no less noisy than
  // the others (below 0 the restricted estimate still outgained the range law on drives).
  const auto best = boost::math::tools::brent_find_minima(
      negative, 0.0, e == Effect::incidence_noise ? 4.0 : 3.0, 30);
  if (statistic) *statistic = std::max(0.0, 2.0 * (negative(0.0) - best.second));
  return best.first;
}

bool noiseShapeEffect(Effect e) {
  return e == Effect::incidence_noise || e == Effect::range_noise_law || e == Effect::heavy_tails ||
         e == Effect::mixed_pixels || e == Effect::dark_surface;
}

/// Candidate c's fit fc with its noise exponent (restrictedShape) at its restricted-likelihood
/// estimate (restrictedShapeEstimate) and the geometry and scale refitted with it held: estimated
/// first under `base` (the baseline on the same data, whose weights no shape has bent) and refitted
/// from its solution, then once more under that refit, refitted again when the estimate moved by
/// more than 0.05. Under the motion prior alone (a pose per scan); otherwise, and for the other
/// effects, fc.
JointResult SequenceDiagnosis::withCorrectedShape(const LandmarkObservations& obs, Effect e,
                                                  const JointResult& base,
                                                  const JointConfig& base_cfg, JointResult fc,
                                                  const JointConfig& fc_cfg,
                                                  double* statistic) const {
  if (!restrictedShape(e) || !baseline_fit_.motion_prior ||
      !baseline_cfg_.effects.estimate_heading || !fc.ok() || !base.ok())
    return fc;
  JointConfig held = warmStartConfig(fc_cfg);
  held.hold_noise_shape = true;
  JointResult from = base;
  from.effects.dark_reference_intensity = fc.effects.dark_reference_intensity;
  double previous = kNaN;
  for (int round = 0; round < 2; ++round) {
    const double v =
        restrictedShapeEstimate(obs, round == 0 ? from : fc, round == 0 ? base_cfg : held, e,
                                round == 0 ? statistic : nullptr);
    if (!std::isfinite(v) || std::abs(v - previous) <= 0.05) break;
    JointInit start = initFrom(round == 0 ? from : fc);
    setNoiseShape(e, v, start);
    JointResult again = refineJoint(obs, start, held);
    if (!again.ok()) break;
    fc = std::move(again);
    previous = v;
  }
  return fc;
}

}  // namespace lidarcal::diagnosis::sequence
