// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/odometry_noise.hpp"

#include "common/pose2.hpp"
#include "common/stats_util.hpp"
#include "diagnosis/sequence/pose_uncertainty.hpp"
#include "diagnosis/sequence/problem.hpp"

namespace lidarcal::diagnosis::sequence {

OdometryNoiseFactors odometryNoiseFactors(const LandmarkObservations& obs, const JointResult& fit,
                                          const JointConfig& cfg) {
  if (std::min(fit.poses.size(), obs.commanded.size()) < 11) return {};
  std::vector<double> t, h;
  double leverage = 0.0;
  forEachLocatedStep(obs, fit, cfg,
                     [&](std::size_t, const OdometryStep& o, const Eigen::Matrix3d& s) {
                       for (int i = 0; i < 3; ++i)
                         (i < 2 ? t : h).push_back(o.r(i) * o.r(i) / std::max(1.0 - s(i, i), 0.05));
                       leverage += s.trace() / 3.0;
                     });
  if (h.size() < 10) return {};
  constexpr double kChi2OneMedian = 0.454936;
  return {std::sqrt(median(t) / kChi2OneMedian), std::sqrt(median(h) / kChi2OneMedian),
          static_cast<double>(t.size()), static_cast<double>(h.size()),
          leverage / static_cast<double>(h.size())};
}

double medianStepLength(const std::vector<Pose2>& commanded) {
  std::vector<double> len;
  for (std::size_t k = 1; k < commanded.size(); ++k) {
    const Pose2 step = stepBetween(commanded[k - 1], commanded[k]);
    len.push_back(std::hypot(step.x_m, step.y_m));
  }
  return len.empty() ? 0.0 : median(len);
}

/// A continuous recording's odometry noise, from its own steps: the motion prior's standard
/// deviations (JointConfig's defaults: a robot's odometry is unknown) scaled by what the baseline's
/// steps show (odometryNoiseFactors), the baseline refitted, until the factors settle (within 2 %,
/// four passes at most). Held at the defaults, a drive's odometry better than them is weighed below
/// its information and path terms go unnamed (docs/results/hidden-effects.md, Robots that never
/// stop).
void SequenceDiagnosis::fitOdometryNoise() {
  const JointConfig prior = baseline_cfg_;
  const JointResult at_prior = baseline_fit_;
  bool settled = false;
  double ft = 1.0, fh = 1.0;  // the factors on the defaults so far
  for (int pass = 0; pass < 4 && !settled; ++pass) {
    const OdometryNoiseFactors f = odometryNoiseFactors(obs_, baseline_fit_, baseline_cfg_);
    odometry_noise_ = f;  // its counts and leverage; the factors on the defaults below
    // The defaults are the loosest the prior gets: steps scattered beyond them are more likely the
    // baseline's misfit (an effect it lacks bends its path) than odometry that bad.
    const double nt = std::min(ft * f.translation, 1.0), nh = std::min(fh * f.heading, 1.0);
    settled = std::abs(std::log(nt / ft)) < 0.02 && std::abs(std::log(nh / fh)) < 0.02;
    if (settled) break;
    // A (per metre, floor) pair scaled by this pass's factor, or back at the defaults when capped.
    const auto rescale = [](double& per_m, double& floor, double factor, bool capped,
                            double prior_per_m, double prior_floor) {
      per_m = capped ? prior_per_m : per_m * factor;
      floor = capped ? prior_floor : floor * factor;
    };
    JointConfig c = baseline_cfg_;
    rescale(c.motion_sigma_fraction, c.motion_sigma_floor_m, f.translation, nt >= 1.0,
            prior.motion_sigma_fraction, prior.motion_sigma_floor_m);
    rescale(c.motion_heading_sigma_rad_per_m, c.motion_heading_floor_rad, f.heading, nh >= 1.0,
            prior.motion_heading_sigma_rad_per_m, prior.motion_heading_floor_rad);
    JointResult again = refineJoint(obs_, initFrom(baseline_fit_), warmStartConfig(c));
    if (!again.ok()) break;
    baseline_cfg_ = c;
    baseline_fit_ = std::move(again);
    ft = nt;
    fh = nh;
  }
  // Where the poses follow the steps (mean leverage above a half) their residuals cannot tell the
  // odometry's noise, and shrinking it draws the poses closer still (poses from SLAM:
  // docs/FINDINGS.md). Then, or when the factors do not settle, the prior's defaults stand.
  odometry_noise_.fitted =
      settled && odometry_noise_.heading_count > 0.0 && odometry_noise_.leverage < 0.5;
  if (!odometry_noise_.fitted) {
    baseline_cfg_ = prior;
    baseline_fit_ = at_prior;
  }
  // floors > 0 (validate)
  odometry_noise_.translation = baseline_cfg_.motion_sigma_floor_m / prior.motion_sigma_floor_m;
  odometry_noise_.heading = baseline_cfg_.motion_heading_floor_rad / prior.motion_heading_floor_rad;
}

}  // namespace lidarcal::diagnosis::sequence
