// SPDX-License-Identifier: BSD-3-Clause
// The joint refinement's result from a solved problem: estimates, the priors' likelihood, the
// effect terms, the likelihood and information criteria, bearing residuals, covariances.
#include "calibration/joint_problem.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "common/information_criteria.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration::joint {
namespace {

constexpr double kWeakCentrePriorSigmaM = 100.0;

}  // namespace

/// Poses, centres, radius and bias into the result; landmark offsets are reported with mean
/// zero, their mean going into alpha_0.
void JointProblem::reportEstimates() {
  if (fx_.landmark_offsets && !offsets_.empty()) {
    double mean = 0.0;
    for (const auto& [id, o] : offsets_) mean += *o / static_cast<double>(offsets_.size());
    for (auto& [id, o] : offsets_) *o -= mean;
    alpha_[0] += mean;
  }
  out_.model.bias.alpha = alphaVector();
  out_.radius_m = *radius_;
  out_.poses.resize(poses_.size());
  double ps = 0.0, hs = 0.0;
  for (std::size_t k = 0; k < poses_.size(); ++k) {
    out_.poses[k] = Pose2{poses_[k][0], poses_[k][1], wrapAngle(poses_[k][2])};
    ps += std::pow(poses_[k][0] - obs_.commanded[k].x_m, 2) +
          std::pow(poses_[k][1] - obs_.commanded[k].y_m, 2);
    hs += std::pow(wrapAngle(poses_[k][2] - obs_.commanded[k].yaw_rad), 2);
  }
  out_.pose_scatter_m = std::sqrt(ps / (2.0 * static_cast<double>(poses_.size())));
  out_.heading_scatter_rad = std::sqrt(hs / static_cast<double>(poses_.size()));
  for (const auto& [id, c] : centres_) out_.centres[id] = Eigen::Vector2d(c[0], c[1]);
}

/// A fitted step scale stays within +-kMaxStepScale: odometry that misjudges its steps by half
/// is broken, not miscalibrated. Unbounded, an incidence bias hidden in a thin-pole drive drew
/// the scale to -0.99 (the path shrunk to a point, its misfit in the steps), which out-gained the
/// bias itself held out (docs/results/hidden-effects.md).
void JointProblem::boundStepScale(ceres::Problem& problem) const {
  if (!fx_.odometry_scale || !problem.HasParameterBlock(scale_) ||
      problem.IsParameterBlockConstant(scale_))
    return;
  problem.SetParameterLowerBound(scale_, 0, -kMaxStepScale);
  problem.SetParameterUpperBound(scale_, 0, kMaxStepScale);
}

/// NLL of the commanded positions (or steps, with the motion prior) given the refined poses.
/// With the motion prior the heading changes (and the first stop's heading) count too, as the
/// refinement weighs them (MotionPriorCost, PosePriorCost): a likelihood ratio of two drives'
/// fits then compares the objectives they minimised. Without it (stops) the headings' prior is
/// left out, as it has been since the stop-and-go diagnosis was calibrated on it.
void JointProblem::reportPriorLikelihood() {
  const Pose2& c0 = obs_.commanded.front();
  const double s = fx_.odometry_scale ? *scale_ : 0.0;
  auto add = [&](double ex, double ey, double sd) {
    out_.prior_neg_log_likelihood +=
        0.5 * (ex * ex + ey * ey) / (sd * sd) + kLog2Pi + 2.0 * std::log(sd);
  };
  auto addHeading = [&](double e, double sd) {
    out_.prior_neg_log_likelihood += 0.5 * e * e / (sd * sd) + 0.5 * kLog2Pi + std::log(sd);
  };
  for (std::size_t k = 0; k < poses_.size(); ++k) {
    if (motion_ && k > 0) {
      const Pose2 step = stepBetween(obs_.commanded[k - 1], obs_.commanded[k]);
      const Pose2 est = stepBetween(out_.poses[k - 1], out_.poses[k]);
      const double len = motionStepLength(obs_.commanded, k);
      // where the noise is (MotionPriorCost)
      add(est.x_m / (1.0 + s) - step.x_m, est.y_m / (1.0 + s) - step.y_m,
          config_.motionStepSigma(len));
      addHeading(wrapAngle(out_.poses[k].yaw_rad - out_.poses[k - 1].yaw_rad - step.yaw_rad),
                 config_.motionHeadingSigma(len));
      continue;
    }
    add(poses_[k][0] - (c0.x_m + (1.0 + s) * (obs_.commanded[k].x_m - c0.x_m)),
        poses_[k][1] - (c0.y_m + (1.0 + s) * (obs_.commanded[k].y_m - c0.y_m)), config_.sigma_s_m);
    if (motion_)
      addHeading(wrapAngle(out_.poses[k].yaw_rad - obs_.commanded[k].yaw_rad),
                 config_.sigma_psi_rad);
  }
}

void JointProblem::reportEffects() {
  JointEffectEstimates& e = out_.effects;
  if (fx_.landmark_offsets)
    for (const auto& [id, o] : offsets_) e.landmark_offset_m[id] = *o;
  e.drift_m_per_scan = fx_.drift ? globals_[0] : 0.0;
  e.angle_offset_rad = fx_.angle_offset ? globals_[1] : 0.0;
  e.incidence_bias_m = fx_.incidence_bias ? globals_[2] : 0.0;
  e.incidence_noise_exponent = gamma_;
  e.noise_exponent = out_.model.noise.kind == NoiseKind::power      ? out_.model.noise.exponent
                     : out_.model.noise.kind == NoiseKind::constant ? 0.0
                                                                    : 2.0;
  e.mixed_pixel_fraction = fx_.mixed_pixels ? mixed_fraction_ : 0.0;
  e.odometry_scale = fx_.odometry_scale ? *scale_ : 0.0;
  e.student_dof = fx_.student_noise ? dof_ : 0.0;
  e.range_grid_m = grid_;
  e.dark_noise_exponent = delta_;
  e.dark_reference_intensity = reference_intensity_;
  e.heading_rms_rad = out_.heading_scatter_rad;
  out_.effect_parameters =
      (fx_.landmark_offsets ? static_cast<int>(offsets_.size()) - 1 : 0) + (fx_.drift ? 1 : 0) +
      (fx_.angle_offset ? 1 : 0) + (fx_.incidence_bias ? 1 : 0) + (fx_.incidence_noise ? 1 : 0) +
      (fx_.noise_exponent ? 1 : 0) + (fx_.mixed_pixels ? 1 : 0) + (fx_.odometry_scale ? 1 : 0) +
      (fx_.student_noise ? 1 : 0) + (fx_.quantised ? 1 : 0) + (fx_.dark_noise ? 1 : 0) +
      (fx_.estimate_heading ? static_cast<int>(poses_.size()) : 0);
}

/// Likelihood at the solution (all readings, with the mixed-pixel and outlier terms) and the
/// information criteria.
void JointProblem::reportLikelihood() {
  updateGeometry();
  const JointEffectEstimates& e = out_.effects;
  out_.neg_log_likelihood = 0.0;
  out_.outliers = 0;
  out_.residual_rms_m = 0.0;
  std::vector<double> d(readings_.size());
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    d[i] = geo_[i].d;
    const double s = std::max(sigmaOf(i, out_.model), 1e-6);
    const double mean = meanOf(i, out_.model.bias);
    const double r = (readings_[i].y_m - mean) / s;
    out_.neg_log_likelihood -= readingLogLikelihood(
        readings_[i].y_m, mean, s,
        ReadingLaw{readings_[i].edge ? e.mixed_pixel_fraction : 0.0, config_.outlier_floor,
                   out_.window_min_m, window_max_, e.student_dof, e.range_grid_m});
    out_.residual_rms_m += r * r * s * s;
    if (std::abs(r) > config_.huber_sigmas * 2.0) ++out_.outliers;
  }
  out_.residual_rms_m = std::sqrt(out_.residual_rms_m / static_cast<double>(readings_.size()));
  out_.readings = readings_.size();
  out_.distances_m = d;
  out_.readings_m.reserve(readings_.size());
  for (const auto& r : readings_) out_.readings_m.push_back(r.y_m);
  const int heading_params = fx_.estimate_heading ? static_cast<int>(poses_.size()) : 0;
  const double k = static_cast<double>(config_.order + 1) +
                   (config_.noise == NoiseKind::polynomial ? config_.noise_order + 1.0 : 1.0) +
                   (config_.estimate_radius ? 1.0 : 0.0) +
                   static_cast<double>(out_.effect_parameters - heading_params);
  out_.aic = akaike(k, out_.neg_log_likelihood);
  out_.bic = schwarz(k, readings_.size(), out_.neg_log_likelihood);
}

/// Centre-bearing residuals: detected centre bearing against the refined geometry.
void JointProblem::reportBearingResiduals() {
  double bs = 0.0;
  std::size_t bn = 0;
  for (const auto& s : obs_.sightings) {
    auto it = out_.centres.find(s.landmark);
    if (it == out_.centres.end() || s.stop >= out_.poses.size()) continue;
    const Pose2& p = out_.poses[s.stop];
    const double predicted = std::atan2(it->second.y() - p.y_m, it->second.x() - p.x_m) -
                             p.yaw_rad - out_.effects.angle_offset_rad;
    bs += std::pow(wrapAngle(s.bearing_rad - predicted), 2);
    ++bn;
  }
  out_.sigma_theta_rad = bn ? std::sqrt(bs / static_cast<double>(bn)) : 0.0;
}

/// Covariance of alpha, the radius and the centres with the final weights; the pose priors fix
/// the gauge.
void JointProblem::computeCovariance() {
  for (std::size_t i = 0; i < readings_.size(); ++i) sigma_[i] = workingSigma(i, out_.model);
  ceres::Problem problem;
  addResiduals(problem, false);
  ceres::Covariance::Options copt;
  // A dense SVD of the whole Jacobian (rank-revealing: a pseudo-inverse where the data leave a
  // direction free) costs readings x parameters memory: over 20 GB for a 4791-pose CARMEN log.
  // Beyond a few hundred poses the sparse QR computes the same blocks (the pose priors make the
  // Jacobian full rank) in memory that grows with the poses.
  if (problem.NumParameters() <= config_.dense_covariance_max_parameters) {
    copt.algorithm_type = ceres::DENSE_SVD;
    copt.null_space_rank = -1;
  } else {
    copt.algorithm_type = ceres::SPARSE_QR;
  }
  auto cov = std::make_unique<ceres::Covariance>(copt);
  std::vector<std::pair<const double*, const double*>> blocks = {{alpha_, alpha_}};
  const bool radius_free = config_.estimate_radius && problem.HasParameterBlock(radius_);
  if (radius_free) {
    blocks.emplace_back(alpha_, radius_);
    blocks.emplace_back(radius_, radius_);
  }
  for (auto& [id, c] : centres_)
    if (problem.HasParameterBlock(c)) blocks.emplace_back(c, c);
  const bool has_alpha = problem.HasParameterBlock(alpha_);
  bool computed = has_alpha && cov->Compute(blocks, &problem);
  if (!computed && has_alpha && copt.algorithm_type == ceres::SPARSE_QR) {
    // The sparse QR needs full rank; a landmark whose few beams leave its centre free along a
    // direction (seen once, edge-on: Freiburg 079) makes it fail where the dense SVD would take
    // a pseudo-inverse. Tie every centre to its estimate with 100 m standard deviation: that
    // removes the null space and changes the determined blocks by about (sigma/100 m)^2.
    for (auto& [id, c] : centres_)
      if (problem.HasParameterBlock(c))
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<WeakPointPriorCost, 2, 2>(
                                     new WeakPointPriorCost{c[0], c[1], kWeakCentrePriorSigmaM}),
                                 nullptr, c);
    cov = std::make_unique<ceres::Covariance>(copt);
    computed = cov->Compute(blocks, &problem);
  }
  if (!computed) return;
  const int n = config_.order + 1;
  out_.alpha_covariance.resize(n, n);
  cov->GetCovarianceBlock(alpha_, alpha_, out_.alpha_covariance.data());
  if (radius_free) {
    out_.alpha_radius_covariance.resize(n);
    cov->GetCovarianceBlock(alpha_, radius_, out_.alpha_radius_covariance.data());
    cov->GetCovarianceBlock(radius_, radius_, &out_.radius_variance);
  }
  for (auto& [id, c] : centres_) {
    if (!problem.HasParameterBlock(c)) continue;
    Eigen::Matrix2d m;
    cov->GetCovarianceBlock(c, c, m.data());
    out_.centre_covariance[id] = m;
  }
}

}  // namespace lidarcal::calibration::joint
