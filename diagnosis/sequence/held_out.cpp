// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/held_out.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "common/pose2.hpp"
#include "common/range_effects.hpp"
#include "common/stats_util.hpp"
#include "diagnosis/sequence/pose_uncertainty.hpp"

namespace lidarcal::diagnosis::sequence {

std::vector<double> heldOutLikelihoods(const LandmarkObservations& train,
                                       const LandmarkObservations& test, const JointResult& fit,
                                       const JointConfig& cfg, std::vector<std::size_t>* scans) {
  const auto rs = evaluateJoint(test, fit, cfg);
  std::vector<double> ll(rs.size());
  if (scans) {
    scans->clear();
    for (const auto& r : rs) scans->push_back(r.scan);
  }
  const bool pose_uncertain = fit.motion_prior && cfg.effects.estimate_heading;
  // The noise at the readings' own variance (noiseDofFactor), and the poses' covariance with it.
  PoseUncertainty u;
  if (pose_uncertain) u = poseUncertainty(train, fit, cfg);
  const double dof = u.dof;
  const std::vector<Eigen::Matrix3d>& cov = u.cov;
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const JointReading& r = rs[i];
    if (!pose_uncertain) {
      ll[i] = r.log_likelihood;
      continue;
    }
    // An incidence bias b moves the reading with the pose as the distance does, b / (r f'(d)) more
    // (poleDistanceMoments): on a thin pole that is most of a held-out reading's spread.
    const double slope = fit.model.bias.derivative(r.d_m), b = fit.effects.incidence_bias_m;
    const double extra =
        b != 0.0 && slope > 0.1 && fit.radius_m > 0.0 ? b / (fit.radius_m * slope) : 0.0;
    const DistanceMoments dm = heldOutDistance(fit, r, cov[r.stop], extra);
    const double at_fit = r.d_m - extra * fit.radius_m * r.cos_incidence;
    const double sigma = std::sqrt(dof * r.sigma_m * r.sigma_m + slope * slope * dm.var);
    const double mean = r.mean_m + slope * (dm.mean - at_fit);
    ll[i] = readingLogLikelihood(
        r.y_m, mean, sigma,
        calibration::ReadingLaw{r.edge ? fit.effects.mixed_pixel_fraction : 0.0, cfg.outlier_floor,
                                fit.window_min_m, fit.window_max_m, fit.effects.student_dof,
                                fit.effects.range_grid_m});
  }
  return ll;
}

std::vector<double> odometryHeldOut(const LandmarkObservations& obs, const JointResult& fit,
                                    const JointConfig& cfg) {
  const std::size_t k_stops = fit.poses.size();
  std::vector<Eigen::Matrix3d> h(k_stops, Eigen::Matrix3d::Zero());
  for (const auto& r : evaluateJoint(obs, fit, cfg)) {
    const Pose2& p = fit.poses[r.stop];
    const auto& c = fit.centres.at(r.landmark);
    const RayGradient g =
        rayGradient(p.x_m, p.y_m, p.yaw_rad + r.angle_rad + fit.effects.angle_offset_rad, c.x(),
                    c.y(), fit.radius_m);
    const double fp = fit.model.bias.derivative(g.d);
    const Eigen::Vector3d j(-fp * g.dcx, -fp * g.dcy, fp * g.da);
    h[r.stop] += j * j.transpose() / (r.sigma_m * r.sigma_m);
  }
  const double s2 = cfg.sigma_s_m * cfg.sigma_s_m;
  const Pose2& c0 = obs.commanded.front();
  const double scale = fit.effects.odometry_scale;
  std::vector<double> out(k_stops, 0.0);
  for (std::size_t k = 0; k < k_stops; ++k) {
    Eigen::Matrix2d hxy = h[k].topLeftCorner<2, 2>();
    if (cfg.effects.estimate_heading) {
      const double hpp = h[k](2, 2) + 1.0 / (cfg.sigma_psi_rad * cfg.sigma_psi_rad);
      hxy -= h[k].topRightCorner<2, 1>() * h[k].bottomLeftCorner<1, 2>() / hpp;
    }
    hxy.diagonal().array() += 1e-9;
    const Eigen::Matrix2d cov_data = hxy.inverse();
    const Eigen::Vector2d c(c0.x_m + (1.0 + scale) * (obs.commanded[k].x_m - c0.x_m),
                            c0.y_m + (1.0 + scale) * (obs.commanded[k].y_m - c0.y_m));
    const Eigen::Vector2d p(fit.poses[k].x_m, fit.poses[k].y_m);
    const Eigen::Vector2d pd = p + cov_data * (p - c) / s2;
    const Eigen::Matrix2d cov = s2 * Eigen::Matrix2d::Identity() + cov_data;
    const Eigen::Vector2d e = c - pd;
    out[k] =
        -std::log(2.0 * kPi) - 0.5 * std::log(cov.determinant()) - 0.5 * e.dot(cov.inverse() * e);
  }
  return out;
}

std::vector<double> stepHeldOut(const LandmarkObservations& obs, const JointResult& fit,
                                const JointConfig& cfg) {
  const std::size_t n = std::min(fit.poses.size(), obs.commanded.size());
  if (n < 2) return {};
  std::vector<double> out(n - 1, kNaN);
  forEachLocatedStep(obs, fit, cfg,
                     [&out](std::size_t k, const OdometryStep& o, const Eigen::Matrix3d& s) {
                       out[k - 1] = leaveOneOutLogDensity(o.r, s) + o.log_scale;
                     });
  return out;
}

}  // namespace lidarcal::diagnosis::sequence
