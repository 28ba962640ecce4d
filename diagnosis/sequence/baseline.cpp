// SPDX-License-Identifier: BSD-3-Clause
// Steps 1 and 2 of a sequence diagnosis: the baseline fitted (two starts, the order, a drive's
// odometry noise), the measured statistics, and the bootstrap replicas refitted from it.

#include <algorithm>
#include <utility>

#include "common/rng.hpp"
#include "diagnosis/sequence/folds.hpp"
#include "diagnosis/sequence/problem.hpp"

namespace lidarcal::diagnosis::sequence {
namespace {

/// AIC of fit `a` (bias order a_order) minus AIC of fit `b` (order b_order).
double aicChange(const JointResult& a, int a_order, const JointResult& b, int b_order) {
  return 2.0 * (totalNegLogLikelihood(a) - totalNegLogLikelihood(b)) + 2.0 * (a_order - b_order);
}

}  // namespace

bool SequenceDiagnosis::fitBaseline(DiagnosisResult& out) {
  if (!calibrateBaseline(out)) return false;
  reading_grid_m_ = readingGrid(obs_);
  intensity_varies_ = intensitiesVary(obs_);
  if (reading_grid_m_ > 0.0)
    dequantised_ = dequantised(obs_, reading_grid_m_, deriveSeed(config_.seed, 0xDE0A7ULL));
  baseline_cfg_ = baselineConfig(calibration_, calibration_cfg_, obs_, config_);
  findStarts();
  chooseOrder();
  if (baseline_fit_.ok() && baseline_fit_.motion_prior) fitOdometryNoise();
  if (!baseline_fit_.ok()) {
    out.status.code = StatusCode::baseline_failed;
    out.status.message = baseline_fit_.status.message;
    return false;
  }
  if (baseline_fit_.motion_prior) {  // settleBaseline needs the candidates' fits
    fitCandidates(false, "baseline fit", candidates_.size());
    baseline_settled_ = settleBaseline();
  }
  describeBaseline(out);
  return true;
}

bool SequenceDiagnosis::calibrateBaseline(DiagnosisResult& out) {
  calibration_cfg_.method = Method::joint;
  calibration_cfg_.max_order = config_.max_order;
  calibration_cfg_.joint.effects.estimate_heading = false;
  calibration_cfg_.joint.sigma_s_m = config_.sigma_s_m;
  calibration_cfg_.triangulation.sigma_s_m = config_.sigma_s_m;
  try {
    calibration_ = calibrate(obs_, calibration_cfg_);
  } catch (const std::invalid_argument& e) {
    calibration_.status.code = StatusCode::calibration_failed;
    calibration_.status.message = e.what();
  }
  if (!calibration_.status.ok()) {
    out.status = calibration_.status;
    out.status.message = "the baseline calibration failed: " + calibration_.status.message;
    return false;
  }
  return true;
}

/// Two starts, the better fit kept (readings and odometry): the calibration's refined solution,
/// and a neutral one that no range effect has bent (landmarks triangulated from bearings alone,
/// commanded poses, the closed form's bias).
void SequenceDiagnosis::findStarts() {
  calibrated_start_.poses = calibration_.stop_poses;
  calibrated_start_.model = calibration_.model;
  calibrated_start_.radius_m = landmarkRadius(obs_);
  for (const auto& l : calibration_.landmarks)
    if (l.ok()) {
      calibrated_start_.centres[l.id] = Eigen::Vector2d(l.x_m, l.y_m);
      calibrated_start_.radius_m = l.radius_m;
    }
  closed_form_order_ = baseline_cfg_.order;
  CalibrationConfig cf = calibration_cfg_;
  cf.method = Method::closed_form;
  const CalibrationModel m = calibrate(obs_, cf);
  if (!m.status.ok()) return;
  JointInit n;
  n.poses = obs_.commanded;
  n.radius_m = calibrated_start_.radius_m;
  for (const auto& l : m.landmarks)
    if (l.ok()) n.centres[l.id] = Eigen::Vector2d(l.x_m, l.y_m);
  n.model = m.model;
  closed_form_order_ = std::max(m.model.bias.order(), 1);
  if (n.centres.size() == calibrated_start_.centres.size()) neutral_start_ = n;
}

JointResult SequenceDiagnosis::bestOf(const JointInit& start, const JointConfig& cfg,
                                      bool both) const {
  JointResult r = refineJoint(obs_, withOrder(start, cfg.order), cfg);
  if (neutral_start_ && both) {
    JointResult other = refineJoint(obs_, withOrder(*neutral_start_, cfg.order), cfg);
    if (totalNegLogLikelihood(other) < totalNegLogLikelihood(r)) r = std::move(other);
  }
  if (cfg.effects.estimate_heading) {
    JointResult other = fitInTwoSteps(obs_, withOrder(start, cfg.order), cfg);
    if (totalNegLogLikelihood(other) < totalNegLogLikelihood(r)) r = std::move(other);
  }
  return r;
}

/// A continuous recording's fit from `start` in two steps: first on the beams that pass through
/// each landmark by the current estimate, re-selected before every solve, under the Huber loss
/// (calibrate's problem, whose objective is smooth), then on every beam under `cfg`. On every beam
/// under the Cauchy loss a pose per scan leaves optima the direct fit cannot leave (a beam put past
/// a thin pole's tangent is predicted at its closest approach, flat in the pose):
/// docs/results/hidden-effects.md, Robots that never stop.
JointResult SequenceDiagnosis::fitInTwoSteps(const LandmarkObservations& obs,
                                             const JointInit& start, const JointConfig& cfg) const {
  JointConfig smooth = cfg;
  smooth.keep_all_beams = false;
  smooth.reselect = true;
  smooth.cauchy_loss = false;
  const JointResult s = refineJoint(obs, start, smooth);
  if (!s.ok()) return s;
  return refineJoint(obs, initFrom(s), cfg);
}

/// The order: the calibration's, or the closed form's when they differ and it fits better by AIC
/// (an effect the baseline lacks can drag the joint refinement to a wrong order).
void SequenceDiagnosis::chooseOrder() {
  baseline_fit_ = bestOf(calibrated_start_, baseline_cfg_);
  if (baseline_fit_.ok() && baseline_fit_.motion_prior) {
    // A continuous recording: the calibration chose its order with every heading held at the
    // drifting odometry's, and the baseline frees them, so every order is tried under the motion
    // prior (AIC); a missing curvature of the bias would pass for effects. Each order's solution is
    // then a start for the chosen order too (a pose per scan leaves many optima).
    std::vector<JointResult> tried;
    for (int order = 1; order <= config_.max_order; ++order) {
      if (order == baseline_cfg_.order) continue;
      JointConfig other = baseline_cfg_;
      other.order = order;
      JointResult alt = bestOf(calibrated_start_, other);
      if (alt.ok() && aicChange(alt, other.order, baseline_fit_, baseline_cfg_.order) < 0.0) {
        std::swap(alt, baseline_fit_);
        baseline_cfg_ = other;
      }
      if (alt.ok()) tried.push_back(std::move(alt));
    }
    for (const JointResult& t : tried) {
      if (t.model.bias.order() == baseline_cfg_.order) continue;
      JointResult again = refineJoint(obs_, withOrder(initFrom(t), baseline_cfg_.order),
                                      warmStartConfig(baseline_cfg_));
      if (totalNegLogLikelihood(again) < totalNegLogLikelihood(baseline_fit_) - 1.0)
        baseline_fit_ = std::move(again);
    }
    return;
  }
  if (closed_form_order_ == baseline_cfg_.order || !neutral_start_) return;
  JointConfig other = baseline_cfg_;
  other.order = closed_form_order_;
  JointResult alt = bestOf(calibrated_start_, other);
  if (alt.ok() && aicChange(alt, other.order, baseline_fit_, baseline_cfg_.order) < 0.0) {
    baseline_fit_ = std::move(alt);
    baseline_cfg_ = other;
  }
}

void SequenceDiagnosis::describeBaseline(DiagnosisResult& out) const {
  out.baseline = baseline_fit_.model;
  out.baseline.range_min_m = obs_.range_min_m;
  out.baseline.range_max_m = obs_.range_max_m;
  out.baseline_sigma_theta_rad = baseline_fit_.sigma_theta_rad;
  out.baseline_radius_m = baseline_fit_.radius_m;
  out.radius_known = obs_.landmark_radius_m.has_value();
  out.baseline_neg_log_likelihood =
      baseline_fit_.neg_log_likelihood + baseline_fit_.prior_neg_log_likelihood;
  out.baseline_extra["pose_scatter_m"] = baseline_fit_.pose_scatter_m;
  out.baseline_extra["sigma_s_prior_m"] = baseline_cfg_.sigma_s_m;
  out.baseline_extra["readings_used"] = static_cast<double>(baseline_fit_.readings);
  out.baseline_extra["motion_prior"] = baseline_fit_.motion_prior ? 1.0 : 0.0;
  if (baseline_fit_.motion_prior) {
    // The odometry's noise as fitted (fitOdometryNoise): the factors on the defaults, their
    // standard errors, and the per-coordinate standard deviations of a typical step.
    const OdometryNoiseFactors& f = odometry_noise_;
    out.baseline_extra["odometry_noise_fitted"] = f.fitted ? 1.0 : 0.0;
    out.baseline_extra["odometry_step_leverage"] = f.leverage;
    out.baseline_extra["odometry_translation_factor"] = f.translation;
    out.baseline_extra["odometry_translation_factor_se"] = f.fitted ? f.translationSe() : 0.0;
    out.baseline_extra["odometry_heading_factor"] = f.heading;
    out.baseline_extra["odometry_heading_factor_se"] = f.fitted ? f.headingSe() : 0.0;
    const double step = medianStepLength(obs_.commanded);
    out.baseline_extra["odometry_step_m"] = step;
    out.baseline_extra["odometry_step_sd_m"] = baseline_cfg_.motionStepSigma(step);
    out.baseline_extra["odometry_step_heading_sd_rad"] = baseline_cfg_.motionHeadingSigma(step);
  }
}

std::map<std::string, double> SequenceDiagnosis::measuredStatistics(DiagnosisResult& out) {
  measured_rows_ = readingRows(obs_, baseline_fit_, baseline_cfg_);
  measured_stats_ = sequenceStatistics(obs_, baseline_fit_, measured_rows_, baseline_cfg_);
  out.measured = residualRecords(measured_rows_);
  appendStandardised(measured_z_, measured_rows_);
  baseline_plan_ = replicaPlan(obs_, baseline_fit_, out.radius_known);
  return measured_stats_;
}

/// A replica's baseline fit, from the data's: under the motion prior also in two steps, as the
/// data were fitted (bestOf), so that the replicas reach optima like the data's.
JointResult SequenceDiagnosis::replicaFit(const LandmarkObservations& rep) const {
  JointResult f = refineJoint(rep, initFrom(baseline_fit_), warmStartConfig(baseline_cfg_));
  if (baseline_cfg_.effects.estimate_heading) {
    JointResult other = fitInTwoSteps(rep, initFrom(baseline_fit_), baseline_cfg_);
    if (totalNegLogLikelihood(other) < totalNegLogLikelihood(f)) f = std::move(other);
  }
  return f;
}

/// One bootstrap replica: simulated from the fitted baseline, refitted from it.
void SequenceDiagnosis::replica(int b, std::map<std::string, std::vector<double>>& stats,
                                DiagnosisResult& out) {
  const LandmarkObservations rep =
      simulateReplica(baseline_plan_, obs_, poseNoise(baseline_fit_, baseline_cfg_),
                      deriveSeed(config_.seed, 1000 + static_cast<std::uint64_t>(b)));
  const JointResult f = replicaFit(rep);
  if (!f.ok()) return;
  const auto rr = readingRows(rep, f, baseline_cfg_);
  for (const auto& [k, v] : sequenceStatistics(rep, f, rr, baseline_cfg_)) stats[k].push_back(v);
  if (b < config_.closeness_replicas) appendStandardised(baseline_replica_z_, rr);
  if (b == 0) out.simulated_baseline = residualRecords(rr);
}

}  // namespace lidarcal::diagnosis::sequence
