// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/joint_stage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "calibration/inversion.hpp"
#include "calibration/noise_fits.hpp"
#include "common/parallel.hpp"

namespace lidarcal::calibration {
namespace {

/// Progress of the stage: the settling pass, one solve per order, the covariance.
class JointProgress {
 public:
  explicit JointProgress(const CalibrationConfig& config)
      : config_(config),
        solves_(1 + static_cast<std::size_t>(config.max_order) +
                (config.joint.covariance ? 1 : 0)) {}
  void report(std::size_t done) const {
    if (config_.progress) config_.progress("joint refinement", done, solves_);
  }
  void finished() const { report(solves_); }

 private:
  const CalibrationConfig& config_;
  std::size_t solves_;
};

/// alpha resized to order n (new coefficients zero).
std::vector<double> alphaAt(int n, std::vector<double> alpha) {
  alpha.resize(static_cast<std::size_t>(n) + 1, 0.0);
  return alpha;
}

/// Start from the closed form's straight-line fit: a higher order chosen by AIC on noisy pairs
/// can extrapolate wildly, a line is a safe start for the bias and the centres.
JointInit closedFormStart(const LandmarkObservations& obs, const CalibrationConfig& config,
                          const std::vector<LandmarkEstimate>& tri, const ClosedFormSeed& seed,
                          double radius, const RangeModel& closed_form_model) {
  const OrderSelection& sel = seed.selection;
  JointInit init;
  init.poses = obs.commanded;
  init.model = closed_form_model;
  init.model.bias.alpha = sel.table[std::min<std::size_t>(1, sel.table.size() - 1)].alpha;
  init.model.noise = fitNoiseLaw(config.noise, 1, init.model.bias, seed.d_m, seed.y_m);
  init.centres = rangeBearingCentres(obs, tri, init.model, radius);
  init.radius_m = radius;
  return init;
}

/// Pass 2: every order 1..max_order from the settled geometry. The orders are independent
/// solves: side by side, each with its own copy of the settings.
std::vector<JointResult> fitEveryOrder(const LandmarkObservations& obs, const JointInit& from,
                                       const JointConfig& jc, const JointResult& settled,
                                       const CalibrationConfig& config) {
  std::vector<JointResult> runs(static_cast<std::size_t>(config.max_order));
  parallelFor(runs.size(), threadsFor(config.threads), [&](std::size_t k) {
    JointConfig jn = jc;
    JointInit fn = from;
    jn.order = static_cast<int>(k) + 1;
    fn.model.bias.alpha = alphaAt(jn.order, settled.model.bias.alpha);
    runs[k] = refineJoint(obs, fn, jn);
  });
  return runs;
}

/// The order table of pass 2, each row marked invertible over the sensor's reading window.
std::vector<OrderRow> orderRows(const std::vector<JointResult>& runs,
                                const LandmarkObservations& obs, const JointProgress& progress) {
  std::vector<OrderRow> rows;
  for (int n = 1; n <= static_cast<int>(runs.size()); ++n) {
    progress.report(1 + static_cast<std::size_t>(n));
    const auto& r = runs[static_cast<std::size_t>(n) - 1];
    OrderRow row;
    row.order = n;
    row.alpha = r.model.bias.alpha;
    row.aic = r.aic;
    row.bic = r.bic;
    row.validation_mse_m2 = row.test_mse_m2 = std::numeric_limits<double>::quiet_NaN();
    rows.push_back(row);
  }
  const bool window_known = obs.range_max_m < 1e8;
  const Admissible ok_order =
      window_known ? invertibleOver(obs.range_min_m, obs.range_max_m) : Admissible{};
  for (auto& row : rows) row.invertible = !ok_order || ok_order(row.alpha);
  return rows;
}

/// The index of the order the rule picks, and (best_aic) that of the smallest admissible AIC.
std::size_t chooseOrder(const std::vector<JointResult>& runs, const std::vector<OrderRow>& rows,
                        JointOrderRule rule, std::size_t& best_aic) {
  best_aic = 0;
  std::size_t best_bic = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!rows[i].invertible) continue;
    if (!rows[best_aic].invertible || runs[i].aic < runs[best_aic].aic) best_aic = i;
    if (!rows[best_bic].invertible || runs[i].bic < runs[best_bic].bic) best_bic = i;
  }
  std::size_t chosen = best_aic;
  if (rule == JointOrderRule::bic) chosen = best_bic;
  if (rule == JointOrderRule::aic_parsimonious)
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (rows[i].invertible && runs[i].aic <= runs[best_aic].aic + 2.0) {
        chosen = i;
        break;
      }
  return chosen;
}

}  // namespace

JointStage jointStage(const LandmarkObservations& obs, const CalibrationConfig& config,
                      const std::vector<LandmarkEstimate>& tri, const ClosedFormSeed& seed,
                      double radius_m, const RangeModel& closed_form_model) {
  JointInit init = closedFormStart(obs, config, tri, seed, radius_m, closed_form_model);
  JointConfig jc = config.joint;
  jc.noise = config.noise;
  jc.estimate_radius = !obs.landmark_radius_m.has_value();
  const JointProgress progress(config);
  progress.report(0);
  // Pass 1: settle the geometry at order 2 (1 if max_order is 1).
  jc.order = std::min(2, config.max_order);
  init.model.bias.alpha = alphaAt(jc.order, init.model.bias.alpha);
  const JointResult settled = refineJoint(obs, init, jc);
  progress.report(1);
  if (!settled.ok()) return JointStage{settled, {}, 0};
  // Pass 2: every order from the settled geometry on one fixed set of readings, so that their
  // information criteria compare likelihoods of the same data.
  const JointInit from = initFrom(settled);
  jc.reselect = false;
  jc.covariance = false;                                   // computed once, for the chosen order
  jc.outer_iterations = std::min(jc.outer_iterations, 2);  // the noise law settled in pass 1
  std::vector<JointResult> runs = fitEveryOrder(obs, from, jc, settled, config);
  const std::vector<OrderRow> rows = orderRows(runs, obs, progress);
  std::size_t best_aic = 0;
  const std::size_t chosen = chooseOrder(runs, rows, config.joint_rule, best_aic);
  if (config.joint.covariance && runs[chosen].ok()) {
    // Covariance at the chosen order: one more (already converged) solve with it switched on.
    jc.order = static_cast<int>(chosen) + 1;
    jc.covariance = true;
    jc.outer_iterations = 1;
    runs[chosen] = refineJoint(obs, initFrom(runs[chosen]), jc);
  }
  progress.finished();
  return JointStage{runs[chosen], rows, best_aic};
}

std::map<int, Eigen::Vector2d> rangeBearingCentres(const LandmarkObservations& obs,
                                                   const std::vector<LandmarkEstimate>& tri,
                                                   const RangeModel& model, double radius) {
  std::map<int, Eigen::Vector2d> sum;
  std::map<int, int> count;
  std::optional<RangeInverter> inverter;
  try {
    inverter.emplace(model, inversionWindow(model, InversionMethod::ls));
  } catch (const std::invalid_argument&) {
  }
  for (const auto& l : tri) {
    if (!l.ok()) continue;
    sum[l.id] = Eigen::Vector2d::Zero();
    count[l.id] = 0;
  }
  for (const auto& s : obs.sightings) {
    auto it = sum.find(s.landmark);
    if (it == sum.end() || s.beams.empty() || !inverter) continue;
    const auto d = inverter->invert(s.beams[centralBeam(s)].range_m);
    if (!d) continue;
    const Pose2& p = obs.commanded.at(s.stop);
    const double a = p.yaw_rad + s.bearing_rad;
    it->second +=
        Eigen::Vector2d(p.x_m + (*d + radius) * std::cos(a), p.y_m + (*d + radius) * std::sin(a));
    ++count[s.landmark];
  }
  std::map<int, Eigen::Vector2d> out;
  for (const auto& l : tri) {
    if (!l.ok()) continue;
    out[l.id] =
        count[l.id] > 0 ? Eigen::Vector2d(sum[l.id] / count[l.id]) : Eigen::Vector2d(l.x_m, l.y_m);
  }
  return out;
}

std::map<std::string, double> effectValues(const JointEffects& on, const JointEffectEstimates& e) {
  std::map<std::string, double> m;
  if (on.landmark_offsets)
    for (const auto& [id, o] : e.landmark_offset_m)
      m["landmark_offset_m[" + std::to_string(id) + "]"] = o;
  if (on.drift) {
    m["range_drift_m_per_scan"] = e.drift_m_per_scan;
    m["range_drift_reference_scan"] = e.drift_reference_scan;
  }
  if (on.angle_offset) m["angle_offset_rad"] = e.angle_offset_rad;
  if (on.incidence_bias) m["incidence_bias_m"] = e.incidence_bias_m;
  if (on.incidence_noise) m["incidence_noise_exponent"] = e.incidence_noise_exponent;
  if (on.noise_exponent) m["noise_exponent"] = e.noise_exponent;
  if (on.mixed_pixels) m["mixed_pixel_fraction"] = e.mixed_pixel_fraction;
  if (on.odometry_scale) m["odometry_scale"] = e.odometry_scale;
  if (on.student_noise) m["noise_student_dof"] = e.student_dof;
  if (on.quantised) m["range_resolution_m"] = e.range_grid_m;
  if (on.dark_noise) {
    m["dark_noise_exponent"] = e.dark_noise_exponent;
    m["dark_reference_intensity"] = e.dark_reference_intensity;
  }
  return m;
}

void fillJoint(CalibrationModel& m, const JointStage& js, const CalibrationConfig& config) {
  const JointResult& j = js.result;
  m.orders = js.rows;
  m.order_rule = toString(config.joint_rule);
  m.order_aic = static_cast<int>(js.best_aic) + 1;
  m.order_validation = -1;
  m.model.bias = j.model.bias;
  m.model.noise = j.model.noise;
  m.sigma_theta_rad = j.sigma_theta_rad;
  m.iterations = j.solver_iterations;
  m.readings = j.readings;
  m.pose_scatter_m = j.pose_scatter_m;
  m.motion_prior = j.motion_prior;
  m.stop_poses = j.poses;
  m.heading_scatter_rad = j.heading_scatter_rad;
  m.residual_rms_m = j.residual_rms_m;
  m.alpha_covariance.assign(j.alpha_covariance.data(),
                            j.alpha_covariance.data() + j.alpha_covariance.size());
  m.effects = effectValues(config.joint.effects, j.effects);
  for (auto& c : m.landmarks) {
    auto it = j.centres.find(c.id);
    if (it == j.centres.end()) continue;
    c.x_m = it->second.x();
    c.y_m = it->second.y();
    c.radius_m = j.radius_m;
    auto cv = j.centre_covariance.find(c.id);
    if (cv != j.centre_covariance.end())
      c.covariance_m2 = {cv->second(0, 0), cv->second(0, 1), cv->second(1, 0), cv->second(1, 1)};
  }
  if (!j.distances_m.empty())
    m.fitted_range_m = fittedRange(j.distances_m, j.readings_m, m.model.bias);
  // usable, but say so
  if (!j.converged) m.status.message = "joint refinement: " + j.status.message;
}

}  // namespace lidarcal::calibration
