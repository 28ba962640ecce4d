// SPDX-License-Identifier: BSD-3-Clause
// The residuals of one solve: the readings (pooled over repeated scans when allowed), the
// measured targets, the pose priors, and which parameter blocks are held fixed.
#include "calibration/joint_problem.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace lidarcal::calibration::joint {

void JointProblem::addResiduals(ceres::Problem& problem, bool robust) {
  const bool pooled = pool_ && addPooledReadings(problem, robust);
  if (!pooled) {
    for (std::size_t i = 0; i < readings_.size(); ++i)
      addReading(problem, robust, readings_[i], readings_[i].angle_rad, readings_[i].y_m,
                 std::sqrt(std::max(weight_[i], 1e-6)) / sigma_[i], 1.0);
    out_.reading_residuals = readings_.size();
  }
  addKnownRanges(problem, robust);
  addPosePriors(problem);
  if (fx_.anyMean()) fixInactiveTerms(problem);
  fixKnownGeometry(problem);
  if (!config_.estimate_radius && problem.HasParameterBlock(radius_))
    problem.SetParameterBlockConstant(radius_);
}

/// `count` readings behind one residual: the loss's threshold scales with sqrt(count), so a
/// pooled residual is down-weighted when its mean is off by huber_sigmas standard deviations of
/// one reading, as a single reading would be (not when it is off by that many standard errors of
/// the mean: a millimetre of geometry error would then put every group there).
void JointProblem::addReading(ceres::Problem& problem, bool robust, const Reading& r, double angle,
                              double y, double inv, double count) {
  ceres::LossFunction* loss = nullptr;
  const double threshold = config_.huber_sigmas * std::sqrt(count);
  if (robust && config_.cauchy_loss)
    loss = new ceres::CauchyLoss(threshold);
  else if (robust)
    loss = new ceres::HuberLoss(threshold);
  if (fx_.anyMean()) {
    problem.AddResidualBlock(
        effectCost(config_.order, angle, y, inv, static_cast<double>(r.scan) - t_ref_), loss,
        poses_[r.stop], centres_.at(r.landmark), radius_, alpha_, offsets_.at(r.landmark),
        globals_);
  } else {
    problem.AddResidualBlock(beamCost(config_.order, angle, y, inv), loss, poses_[r.stop],
                             centres_.at(r.landmark), radius_, alpha_);
  }
}

/// One residual per stop, landmark and beam (the repeated scans' count and mean). False, adding
/// nothing, when every reading is alone (a pose per scan).
bool JointProblem::addPooledReadings(ceres::Problem& problem, bool robust) {
  struct Pooled {
    std::size_t first = 0, n = 0;
    double sum_y = 0.0, sum_angle = 0.0;
  };
  // Key: stop, landmark, beam angle to 1e-5 rad (angles recovered from float coordinates differ
  // by ~1e-7 from scan to scan; beams are 1e-3 rad apart or more), and with the dark-surface
  // term the darkness (readings of one sigma only; with it off the key's last part is 0, so the
  // groups are those of the fit without the term). Ordered: the residuals go in in one order
  // whatever the order of the readings.
  std::map<std::tuple<std::size_t, int, long long, long long>, Pooled> groups;
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    const auto& r = readings_[i];
    const long long dark = fx_.dark_noise ? std::llround(r.darkness * 1e6) : 0;
    Pooled& g = groups[{r.stop, r.landmark, std::llround(r.angle_rad * 1e5), dark}];
    if (g.n == 0) g.first = i;
    ++g.n;
    g.sum_y += r.y_m;
    g.sum_angle += r.angle_rad;
  }
  if (groups.size() >= readings_.size()) return false;
  for (const auto& [key, g] : groups) {
    const double n = static_cast<double>(g.n);
    addReading(problem, robust, readings_[g.first], g.sum_angle / n, g.sum_y / n,
               std::sqrt(n) / sigma_[g.first], n);
  }
  out_.reading_residuals = groups.size();
  return true;
}

/// The measured targets (JointConfig::known_ranges, Alhashimi et al. 2016 section 5 beside the
/// self-calibration): the standard error of a target's mean reading is the readings' sigma(d) /
/// sqrt(n) and its tape error carried through the slope, f'(d) tape_sigma, both at the current
/// estimate.
void JointProblem::addKnownRanges(ceres::Problem& problem, bool robust) {
  RangeModel current = out_.model;
  current.bias.alpha = alphaVector();
  for (const KnownRange& k : config_.known_ranges) {
    const double n = k.count();
    if (!(n > 0.0)) continue;
    const double d = k.meanDistance(*radius_),
                 reading = std::max(current.noise.stddev(d, current.bias), 1e-4);
    const double tape = current.bias.derivative(d) * k.tape_sigma_m;
    const double sigma = std::sqrt(reading * reading / n + tape * tape);
    ceres::LossFunction* loss = robust ? new ceres::HuberLoss(config_.huber_sigmas) : nullptr;
    problem.AddResidualBlock(knownRangeCost(config_.order, k, 1.0 / std::max(sigma, 1e-6)), loss,
                             alpha_, radius_);
  }
}

/// Each stop tied to its commanded pose (Alhashimi et al. 2021 eq. 8; with the odometry scale, to
/// the scaled commanded path), or with the motion prior to the commanded step from the stop before
/// (the first stop's prior fixes the gauge).
void JointProblem::addPosePriors(ceres::Problem& problem) {
  const Pose2& c0 = obs_.commanded.front();
  for (std::size_t k = 0; k < poses_.size(); ++k) {
    const Pose2& c = obs_.commanded[k];
    // unwrapped next to the estimate
    const double yaw = poses_[k][2] + wrapAngle(c.yaw_rad - poses_[k][2]);
    if (motion_ && k > 0) {
      const Pose2 step = stepBetween(obs_.commanded[k - 1], c);
      const double now = poses_[k][2] - poses_[k - 1][2];
      const double len = motionStepLength(obs_.commanded, k);
      problem.AddResidualBlock(
          new MotionPriorAnalyticCost(MotionPriorCost{
              step.x_m, step.y_m, now + wrapAngle(step.yaw_rad - now),
              1.0 / config_.motionStepSigma(len), 1.0 / config_.motionHeadingSigma(len)}),
          nullptr, poses_[k - 1], poses_[k], scale_);
      if (!fx_.odometry_scale) problem.SetParameterBlockConstant(scale_);
    } else if (fx_.odometry_scale) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<ScaledPosePriorCost, 3, 3, 1>(
              new ScaledPosePriorCost{c.x_m, c.y_m, yaw, c0.x_m, c0.y_m, 1.0 / config_.sigma_s_m,
                                      1.0 / config_.sigma_psi_rad}),
          nullptr, poses_[k], scale_);
    } else {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<PosePriorCost, 3, 3>(new PosePriorCost{
              c.x_m, c.y_m, yaw, 1.0 / config_.sigma_s_m, 1.0 / config_.sigma_psi_rad}),
          nullptr, poses_[k]);
    }
    if (!fx_.estimate_heading && problem.HasParameterBlock(poses_[k]))
      problem.SetManifold(poses_[k], new ceres::SubsetManifold(3, {2}));
  }
  boundStepScale(problem);
}

/// Offsets: the first landmark is the reference (its offset is alpha_0's); others free when on.
/// The global terms that are off are held at zero.
void JointProblem::fixInactiveTerms(ceres::Problem& problem) {
  bool first = true;
  for (auto& [id, o] : offsets_) {
    if (!problem.HasParameterBlock(o)) continue;
    if (first || !fx_.landmark_offsets) problem.SetParameterBlockConstant(o);
    first = false;
  }
  std::vector<int> fixed;
  if (!fx_.drift) fixed.push_back(0);
  if (!fx_.angle_offset) fixed.push_back(1);
  if (!fx_.incidence_bias) fixed.push_back(2);
  if (fixed.size() == 3)
    problem.SetParameterBlockConstant(globals_);
  else if (!fixed.empty())
    problem.SetManifold(globals_, new ceres::SubsetManifold(3, fixed));
}

/// Surveyed centres and measured poses are known, not estimated.
void JointProblem::fixKnownGeometry(ceres::Problem& problem) {
  for (const auto& [id, c] : config_.known_centres)
    if (auto it = centres_.find(id); it != centres_.end() && problem.HasParameterBlock(it->second))
      problem.SetParameterBlockConstant(it->second);
  for (const auto& [k, p] : config_.known_poses)
    if (k < poses_.size() && problem.HasParameterBlock(poses_[k]))
      problem.SetParameterBlockConstant(poses_[k]);
}
}  // namespace lidarcal::calibration::joint
