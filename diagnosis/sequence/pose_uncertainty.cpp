// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/pose_uncertainty.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "common/pose2.hpp"

namespace lidarcal::diagnosis::sequence {

RayGradient rayGradient(double px, double py, double a, double cx, double cy, double r) {
  RayGradient g;
  const double c = std::cos(a), s = std::sin(a);
  const double dx = cx - px, dy = cy - py;
  const double along = dx * c + dy * s, perp = dy * c - dx * s;
  const double disc = r * r - perp * perp;
  g.d = rayCircleDistance(px, py, a, cx, cy, r);
  if (disc <= 0.0) {
    g.dcx = c;
    g.dcy = s;
    g.da = perp;
    return g;
  }
  const double sq = std::max(std::sqrt(disc), 0.05 * r);
  g.dcx = c - perp / sq * s;
  g.dcy = s + perp / sq * c;
  g.dr = -r / sq;
  g.da = perp * (1.0 - along / sq);
  return g;
}

Eigen::Vector3d poseGradient(const JointResult& fit, const JointReading& r) {
  const Pose2& p = fit.poses[r.stop];
  const auto& c = fit.centres.at(r.landmark);
  const RayGradient g =
      rayGradient(p.x_m, p.y_m, p.yaw_rad + r.angle_rad + fit.effects.angle_offset_rad, c.x(),
                  c.y(), fit.radius_m);
  return fit.model.bias.derivative(g.d) * Eigen::Vector3d(-g.dcx, -g.dcy, g.da);
}

DistanceMoments heldOutDistance(const JointResult& fit, const JointReading& r,
                                const Eigen::Matrix3d& cov, double root_extra) {
  const Pose2& p = fit.poses[r.stop];
  const auto& centre = fit.centres.at(r.landmark);
  const double a = p.yaw_rad + r.angle_rad + fit.effects.angle_offset_rad;
  const double c = std::cos(a), s = std::sin(a), dx = centre.x() - p.x_m, dy = centre.y() - p.y_m;
  const double along = dx * c + dy * s, perp = dy * c - dx * s;
  Eigen::Matrix<double, 2, 3> j;  // (along, perp) by the pose (x, y, heading)
  j << -c, -s, perp, s, -c, -along;
  return poleDistanceMoments(along, perp, j * cov * j.transpose(), fit.radius_m, root_extra);
}

std::vector<PoseInformation> poseInformation(const LandmarkObservations& obs,
                                             const JointResult& fit, const JointConfig& cfg) {
  std::vector<PoseInformation> out;
  for (const auto& r : evaluateJoint(obs, fit, cfg))
    out.push_back({r.stop, poseGradient(fit, r), r.sigma_m});
  return out;
}

OdometryStep odometryStep(const LandmarkObservations& obs, const JointResult& fit,
                          const JointConfig& cfg, std::size_t a, std::size_t b) {
  const Pose2 step = stepBetween(obs.commanded[a], obs.commanded[b]);
  double sd_t = 0.0, sd_h = 0.0;
  for (std::size_t k = a + 1; k <= b; ++k) {  // the steps' variances add up over a run of them
    const double len = motionStepLength(obs.commanded, k);
    sd_t = std::hypot(sd_t, cfg.motionStepSigma(len));
    sd_h = std::hypot(sd_h, cfg.motionHeadingSigma(len));
  }
  const double t = 1.0 / sd_t, h = 1.0 / sd_h;
  const Pose2 &pa = fit.poses[a], &pb = fit.poses[b];
  const double c = std::cos(pa.yaw_rad), s = std::sin(pa.yaw_rad), ex = pb.x_m - pa.x_m,
               ey = pb.y_m - pa.y_m;
  const double along = c * ex + s * ey, across = c * ey - s * ex,
               f = 1.0 + fit.effects.odometry_scale;
  OdometryStep o;
  o.r = Eigen::Vector3d((along / f - step.x_m) * t, (across / f - step.y_m) * t,
                        wrapAngle(pb.yaw_rad - pa.yaw_rad - step.yaw_rad) * h);
  const double tf = t / f;
  o.ja << -c * tf, -s * tf, across * tf, s * tf, -c * tf, -along * tf, 0.0, 0.0, -h;
  o.jb << c * tf, s * tf, 0.0, -s * tf, c * tf, 0.0, 0.0, 0.0, h;
  o.inv_t = t;
  o.log_scale = 2.0 * std::log(t) + std::log(h);
  return o;
}

PoseChain poseChainInformation(const std::vector<PoseInformation>& readings,
                               const LandmarkObservations& obs, const JointResult& fit,
                               const JointConfig& cfg, double noise_scale) {
  const std::size_t n = fit.poses.size();
  PoseChain chain;
  auto& a = chain.a;
  auto& b = chain.b;
  a.assign(n, Eigen::Matrix3d::Zero());
  b.assign(n, Eigen::Matrix3d::Zero());
  if (n == 0) return chain;
  for (const auto& r : readings)
    a[r.stop] += r.g * r.g.transpose() / (noise_scale * r.sigma * r.sigma);
  a[0].diagonal() +=
      Eigen::Vector3d(1.0 / (cfg.sigma_s_m * cfg.sigma_s_m), 1.0 / (cfg.sigma_s_m * cfg.sigma_s_m),
                      1.0 / (cfg.sigma_psi_rad * cfg.sigma_psi_rad));
  for (std::size_t k = 1; k < n && k < obs.commanded.size(); ++k) {
    const OdometryStep o = odometryStep(obs, fit, cfg, k - 1, k);
    a[k - 1] += o.ja.transpose() * o.ja;
    a[k] += o.jb.transpose() * o.jb;
    b[k - 1] += o.ja.transpose() * o.jb;
  }
  return chain;
}

std::vector<Eigen::Matrix3d> poseCovariances(const std::vector<PoseInformation>& readings,
                                             const LandmarkObservations& obs,
                                             const JointResult& fit, const JointConfig& cfg,
                                             double noise_scale,
                                             std::vector<Eigen::Matrix3d>* upper) {
  const PoseChain chain = poseChainInformation(readings, obs, fit, cfg, noise_scale);
  if (chain.a.empty()) return {};
  return blockTridiagonalInverseDiagonal(chain.a, chain.b, upper);
}

double noiseDofFactor(const std::vector<PoseInformation>& readings,
                      const std::vector<Eigen::Matrix3d>& cov) {
  double h = 0.0;
  for (const auto& r : readings) h += r.g.dot(cov[r.stop] * r.g) / (r.sigma * r.sigma);
  const double n = static_cast<double>(readings.size());
  return n > h + 1.0 ? n / (n - h) : 1.0;
}

PoseUncertainty poseUncertainty(const LandmarkObservations& obs, const JointResult& fit,
                                const JointConfig& cfg, std::vector<Eigen::Matrix3d>* upper) {
  PoseUncertainty u;
  u.info = poseInformation(obs, fit, cfg);
  u.dof = noiseDofFactor(u.info, poseCovariances(u.info, obs, fit, cfg, 1.0));
  u.cov = poseCovariances(u.info, obs, fit, cfg, u.dof, upper);
  return u;
}

}  // namespace lidarcal::diagnosis::sequence
