// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/starts.hpp"

#include <algorithm>
#include <cmath>

#include "common/pose2.hpp"
#include "diagnosis/sequence/problem.hpp"

namespace lidarcal::diagnosis::sequence {

std::pair<double, double> pathCentroid(const std::vector<Pose2>& path) {
  double cx = 0.0, cy = 0.0;
  for (const auto& p : path) {
    cx += p.x_m / static_cast<double>(path.size());
    cy += p.y_m / static_cast<double>(path.size());
  }
  return {cx, cy};
}

double pathSpread(const std::vector<Pose2>& path) {
  const auto [cx, cy] = pathCentroid(path);
  double info = 0.0;
  for (const auto& c : path) info += (c.x_m - cx) * (c.x_m - cx) + (c.y_m - cy) * (c.y_m - cy);
  return info;
}

void turnStart(JointInit& start, double turn, const std::vector<Pose2>& path) {
  const auto [cx, cy] = pathCentroid(path);
  const double ct = std::cos(turn), st = std::sin(turn);
  auto rotate = [&](double& x, double& y) {
    const double dx = x - cx, dy = y - cy;
    x = cx + ct * dx - st * dy;
    y = cy + st * dx + ct * dy;
  };
  for (auto& p : start.poses) rotate(p.x_m, p.y_m);
  for (auto& [id, c] : start.centres) rotate(c.x(), c.y());
  start.effects.angle_offset_rad = turn;
}

std::pair<double, double> stepTurnAndStretch(const LandmarkObservations& obs,
                                             const JointResult& fit, const JointConfig& cfg) {
  double turn = 0.0, stretch = 0.0, info = 0.0;
  const double f = 1.0 + fit.effects.odometry_scale;
  for (std::size_t k = 1; k < std::min(fit.poses.size(), obs.commanded.size()); ++k) {
    const Pose2 cmd = stepBetween(obs.commanded[k - 1], obs.commanded[k]),
                got = stepBetween(fit.poses[k - 1], fit.poses[k]);
    const double len = f * std::hypot(cmd.x_m, cmd.y_m);
    if (!(len > 1e-6)) continue;
    const double sd = cfg.motionStepSigma(motionStepLength(obs.commanded, k)),
                 w = len * len / (sd * sd);
    turn += w * wrapAngle(std::atan2(got.y_m, got.x_m) - std::atan2(cmd.y_m, cmd.x_m));
    stretch += w * ((got.x_m * cmd.x_m + got.y_m * cmd.y_m) * f / (len * len) - 1.0);
    info += w;
  }
  return info > 0.0 ? std::make_pair(turn / info, stretch / info) : std::make_pair(0.0, 0.0);
}

/// The path terms start from what the baseline's refined path shows (the baseline's optimum is
/// a stationary point of the extended models along them): its rotation and stretch against
/// the commanded path.
JointInit SequenceDiagnosis::candidateStart(Effect e) const {
  if (baseline_fit_.motion_prior) return driveStart(e, baseline_fit_);
  const double sqrt_info = std::sqrt(std::max(pathSpread(obs_.commanded), 1e-12));
  JointInit start = initFrom(baseline_fit_);
  // Turn the baseline's world (which turned to absorb the offset) back onto the commanded
  // path, and let the beams turn instead.
  if (e == Effect::angle_offset)
    turnStart(start, -measured_stats_.at("path_rotation") * baseline_cfg_.sigma_s_m / sqrt_info,
              obs_.commanded);
  if (e == Effect::odometry_scale)
    start.effects.odometry_scale =
        measured_stats_.at("path_scale") * baseline_cfg_.sigma_s_m / sqrt_info;
  return start;
}

/// A continuous recording's start for effect e from `from`: the path terms from what its
/// odometry steps show (stepTurnAndStretch). The steps turned by phi in the frame of each scan:
/// the headings turn by phi and the beams back by as much (the angle offset); they stretched by
/// 1 + s: the odometry scale starts at s.
JointInit SequenceDiagnosis::driveStart(Effect e, const JointResult& from) const {
  JointInit start = initFrom(from);
  if (!pathTerm(e)) return start;
  const auto [turn, stretch] = stepTurnAndStretch(obs_, from, baseline_cfg_);
  if (e == Effect::angle_offset) {
    for (auto& p : start.poses) p.yaw_rad += turn;
    start.effects.angle_offset_rad -= turn;
  }
  if (e == Effect::odometry_scale)
    start.effects.odometry_scale = (1.0 + from.effects.odometry_scale) * (1.0 + stretch) - 1.0;
  return start;
}

/// The baseline's start from a candidate's solution: under the motion prior an angle offset goes
/// back into the headings (the beams keep their directions; dropped alone, it turns every beam of
/// a drive and the baseline's refit stops short of its optimum).
JointInit SequenceDiagnosis::baselineStart(const JointResult& from) const {
  JointInit start = initFrom(from);
  if (!from.motion_prior) return start;
  for (auto& p : start.poses) p.yaw_rad += from.effects.angle_offset_rad;
  start.effects.angle_offset_rad = 0.0;
  return start;
}

}  // namespace lidarcal::diagnosis::sequence
