#include "calibration/joint_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>

#include "calibration/range_model_fit.hpp"

namespace lidarcal::calibration {
namespace {

constexpr double kLog2Pi = 1.8378770664093453;

/// Residual of one beam reading: (y - f(d(pose, centre, radius))) / sigma_i, N = order + 1.
template <int N>
struct BeamRangeCost {
  double angle_rad, y_m, inv_sigma;
  template <typename T>
  bool operator()(const T* pose, const T* centre, const T* radius, const T* alpha, T* residual) const {
    const T a = pose[2] + T(angle_rad);
    const T d = rayCircleDistance(pose[0], pose[1], a, centre[0], centre[1], radius[0]);
    T f = alpha[N - 1];
    for (int i = N - 2; i >= 0; --i) f = f * d + alpha[i];
    residual[0] = (T(y_m) - f) * T(inv_sigma);
    return true;
  }
};

/// Prior of a stop pose around its commanded value.
struct PosePriorCost {
  double x, y, yaw, inv_s, inv_psi;
  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    residual[0] = (pose[0] - T(x)) * T(inv_s);
    residual[1] = (pose[1] - T(y)) * T(inv_s);
    // Headings stay within a few degrees of the command: a plain difference is fine once the
    // commanded value is unwrapped next to the estimate (done when the pose is initialised).
    residual[2] = (pose[2] - T(yaw)) * T(inv_psi);
    return true;
  }
};

template <int N>
ceres::CostFunction* makeBeamCost(double angle, double y, double inv_sigma) {
  return new ceres::AutoDiffCostFunction<BeamRangeCost<N>, 1, 3, 2, 1, N>(new BeamRangeCost<N>{angle, y, inv_sigma});
}

ceres::CostFunction* beamCost(int order, double angle, double y, double inv_sigma) {
  switch (order + 1) {
    case 2: return makeBeamCost<2>(angle, y, inv_sigma);
    case 3: return makeBeamCost<3>(angle, y, inv_sigma);
    case 4: return makeBeamCost<4>(angle, y, inv_sigma);
    case 5: return makeBeamCost<5>(angle, y, inv_sigma);
    case 6: return makeBeamCost<6>(angle, y, inv_sigma);
    case 7: return makeBeamCost<7>(angle, y, inv_sigma);
    default: throw std::invalid_argument("refineJoint: order must be 1..6");
  }
}

struct Reading {
  std::size_t stop;
  int landmark;
  double angle_rad;
  double y_m;
};

}  // namespace

void JointConfig::validate() const {
  if (order < 1 || order > 6) throw std::invalid_argument("JointConfig: order must be 1..6");
  if (noise != NoiseKind::squared && noise != NoiseKind::polynomial && noise != NoiseKind::constant)
    throw std::invalid_argument("JointConfig: noise must be squared, polynomial or constant");
  if (!(sigma_s_m > 0.0) || !(sigma_psi_rad > 0.0)) throw std::invalid_argument("JointConfig: priors must be positive");
  if (!(huber_sigmas > 0.0)) throw std::invalid_argument("JointConfig: huber_sigmas must be positive");
  if (!(lateral_fraction > 0.0 && lateral_fraction <= 1.0))
    throw std::invalid_argument("JointConfig: lateral_fraction must be in (0, 1]");
  if (outer_iterations < 1) throw std::invalid_argument("JointConfig: outer_iterations must be >= 1");
}

JointResult refineJoint(const LandmarkObservations& obs, const JointInit& init, const JointConfig& config) {
  config.validate();
  if (init.poses.size() != obs.commanded.size()) throw std::invalid_argument("refineJoint: one initial pose per stop");

  JointResult out;
  out.model = init.model;
  out.model.bias.alpha.resize(static_cast<std::size_t>(config.order) + 1, 0.0);
  out.model.noise.kind = config.noise;
  if (config.noise == NoiseKind::polynomial && out.model.noise.beta.empty())
    out.model.noise.beta.assign(static_cast<std::size_t>(config.noise_order) + 1, 0.0);

  // Parameter blocks.
  std::vector<std::array<double, 3>> poses(init.poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    poses[k] = {init.poses[k].x_m, init.poses[k].y_m, init.poses[k].yaw_rad};
  }
  std::map<int, std::array<double, 2>> centres;
  for (const auto& [id, c] : init.centres) centres[id] = {c.x(), c.y()};
  double radius = init.radius_m;
  std::vector<double> alpha = out.model.bias.alpha;

  // Readings on the central part of each landmark (lateral offset < fraction * radius): beams
  // near the edges have range derivatives that blow up at the tangent. Re-selected from the
  // current estimate before every solve.
  std::vector<Reading> readings;
  auto selectReadings = [&]() {
    readings.clear();
    for (const auto& s : obs.sightings) {
      auto it = centres.find(s.landmark);
      if (it == centres.end() || s.stop >= poses.size()) continue;
      const auto& p = poses[s.stop];
      for (const auto& b : s.beams) {
        if (!std::isfinite(b.range_m)) continue;
        const double a = p[2] + b.angle_rad;
        const double perp = (it->second[1] - p[1]) * std::cos(a) - (it->second[0] - p[0]) * std::sin(a);
        if (std::abs(perp) < config.lateral_fraction * radius) readings.push_back({s.stop, s.landmark, b.angle_rad, b.range_m});
      }
    }
  };
  selectReadings();
  if (readings.size() < static_cast<std::size_t>(config.order + 2) * 4) {
    out.message = "too few landmark readings for the joint refinement (" + std::to_string(readings.size()) + ")";
    return out;
  }

  std::vector<double> d, sigma;
  auto predict = [&](std::size_t i) {
    const auto& r = readings[i];
    const auto& p = poses[r.stop];
    const auto& c = centres.at(r.landmark);
    return rayCircleDistance(p[0], p[1], p[2] + r.angle_rad, c[0], c[1], radius);
  };

  // Size of the noise law, to tell when its re-estimation has settled.
  auto noiseScale = [&](const NoiseModel& n) {
    if (n.kind == NoiseKind::polynomial) return n.beta.empty() ? 0.0 : std::abs(n.beta.front()) + std::abs(n.beta.back());
    return n.sigma_e;
  };
  double previous_scale = noiseScale(out.model.noise);
  // Iteration 0 settles the geometry (poses, centres, radius) with the starting bias held;
  // later iterations free everything and re-estimate the noise law in between.
  for (int outer = 0; outer <= config.outer_iterations; ++outer) {
    out.outer_iterations = outer;
    if (outer > 0 && config.reselect) selectReadings();
    d.resize(readings.size());
    sigma.resize(readings.size());
    for (std::size_t i = 0; i < readings.size(); ++i) d[i] = predict(i);
    RangeModel current = out.model;
    current.bias.alpha = alpha;
    for (std::size_t i = 0; i < readings.size(); ++i) sigma[i] = std::max(current.noise.stddev(d[i], current.bias), 1e-4);

    ceres::Problem::Options problem_options;
    ceres::Problem problem(problem_options);
    for (std::size_t i = 0; i < readings.size(); ++i) {
      const auto& r = readings[i];
      problem.AddResidualBlock(beamCost(config.order, r.angle_rad, r.y_m, 1.0 / sigma[i]),
                               new ceres::HuberLoss(config.huber_sigmas), poses[r.stop].data(),
                               centres.at(r.landmark).data(), &radius, alpha.data());
    }
    for (std::size_t k = 0; k < poses.size(); ++k) {
      const Pose2& c = obs.commanded[k];
      const double yaw = poses[k][2] + wrapAngle(c.yaw_rad - poses[k][2]);  // unwrapped next to the estimate
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PosePriorCost, 3, 3>(new PosePriorCost{
                                   c.x_m, c.y_m, yaw, 1.0 / config.sigma_s_m, 1.0 / config.sigma_psi_rad}),
                               nullptr, poses[k].data());
    }
    if (!problem.HasParameterBlock(alpha.data())) {
      out.message = "no landmark reading left to fit";
      return out;
    }
    if (!config.estimate_radius) problem.SetParameterBlockConstant(&radius);
    else problem.SetParameterLowerBound(&radius, 0, 1e-3);
    if (outer == 0) problem.SetParameterBlockConstant(alpha.data());

    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_SCHUR;  // eliminates the pose or centre blocks
    options.max_num_iterations = config.max_solver_iterations;
    options.function_tolerance = 1e-10;
    options.parameter_tolerance = 1e-10;
    options.num_threads = 1;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    out.solver_iterations += static_cast<int>(summary.iterations.size());
    out.converged = summary.termination_type == ceres::CONVERGENCE;
    if (!summary.IsSolutionUsable()) {
      out.message = "Ceres did not find a usable solution: " + summary.message;
      out.converged = false;
      return out;
    }

    if (outer == 0) continue;
    // Re-estimate the noise law from the readings that are not outliers.
    for (std::size_t i = 0; i < readings.size(); ++i) d[i] = predict(i);
    current.bias.alpha = alpha;
    std::vector<double> din, rin;
    for (std::size_t i = 0; i < readings.size(); ++i) {
      const double res = readings[i].y_m - current.bias(d[i]);
      if (std::abs(res) <= 4.0 * sigma[i]) {
        din.push_back(d[i]);
        rin.push_back(res);
      }
    }
    switch (config.noise) {
      case NoiseKind::squared: {
        double s = 0.0;
        for (std::size_t i = 0; i < din.size(); ++i) {
          const double f = current.bias(din[i]);
          s += rin[i] * rin[i] / (f * f * f * f);
        }
        out.model.noise.sigma_e = std::sqrt(s / static_cast<double>(std::max<std::size_t>(din.size(), 1)));
        break;
      }
      case NoiseKind::constant: {
        double s = 0.0;
        for (double v : rin) s += v * v;
        out.model.noise.sigma_e = std::sqrt(s / static_cast<double>(std::max<std::size_t>(rin.size(), 1)));
        break;
      }
      default: out.model.noise.beta = fitNoisePolynomial(din, rin, config.noise_order); break;
    }
    const double scale = noiseScale(out.model.noise);
    if (previous_scale > 0.0 && std::abs(scale - previous_scale) <= 1e-2 * previous_scale) break;
    previous_scale = scale;
    if (outer == config.outer_iterations) {
      out.converged = false;
      out.message = "noise model still changing after " + std::to_string(config.outer_iterations) + " re-estimations";
    }
  }

  out.model.bias.alpha = alpha;
  out.radius_m = radius;
  out.poses.resize(poses.size());
  double ps = 0.0, hs = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    out.poses[k] = Pose2{poses[k][0], poses[k][1], wrapAngle(poses[k][2])};
    ps += std::pow(poses[k][0] - obs.commanded[k].x_m, 2) + std::pow(poses[k][1] - obs.commanded[k].y_m, 2);
    hs += std::pow(wrapAngle(poses[k][2] - obs.commanded[k].yaw_rad), 2);
  }
  out.pose_scatter_m = std::sqrt(ps / (2.0 * static_cast<double>(poses.size())));
  out.heading_scatter_rad = std::sqrt(hs / static_cast<double>(poses.size()));
  for (const auto& [id, c] : centres) out.centres[id] = Eigen::Vector2d(c[0], c[1]);

  // Likelihood at the solution (plain Gaussian, all readings) and information criteria.
  out.neg_log_likelihood = 0.0;
  out.outliers = 0;
  for (std::size_t i = 0; i < readings.size(); ++i) {
    const double s = std::max(out.model.noise.stddev(d[i], out.model.bias), 1e-6);
    const double r = (readings[i].y_m - out.model.bias(d[i])) / s;
    out.neg_log_likelihood += 0.5 * (kLog2Pi + 2.0 * std::log(s) + r * r);
    out.residual_rms_m += r * r * s * s;
    if (std::abs(r) > config.huber_sigmas * 2.0) ++out.outliers;
  }
  out.residual_rms_m = std::sqrt(out.residual_rms_m / static_cast<double>(readings.size()));
  out.distances_m = d;
  out.readings_m.reserve(readings.size());
  for (const auto& r : readings) out.readings_m.push_back(r.y_m);
  const double k = static_cast<double>(config.order + 1) +
                   (config.noise == NoiseKind::polynomial ? config.noise_order + 1.0 : 1.0) + (config.estimate_radius ? 1.0 : 0.0);
  out.aic = 2.0 * k + 2.0 * out.neg_log_likelihood;
  out.bic = k * std::log(static_cast<double>(readings.size())) + 2.0 * out.neg_log_likelihood;

  // Centre-bearing residuals: detected centre bearing vs the refined geometry.
  double bs = 0.0;
  std::size_t bn = 0;
  for (const auto& s : obs.sightings) {
    auto it = out.centres.find(s.landmark);
    if (it == out.centres.end() || s.stop >= out.poses.size()) continue;
    const Pose2& p = out.poses[s.stop];
    const double predicted = std::atan2(it->second.y() - p.y_m, it->second.x() - p.x_m) - p.yaw_rad;
    bs += std::pow(wrapAngle(s.bearing_rad - predicted), 2);
    ++bn;
  }
  out.sigma_theta_rad = bn ? std::sqrt(bs / static_cast<double>(bn)) : 0.0;

  if (config.covariance) {
    // Covariance of alpha and the centres with the final weights; the pose priors fix the gauge.
    ceres::Problem problem;
    for (std::size_t i = 0; i < readings.size(); ++i) {
      const auto& r = readings[i];
      const double s = std::max(out.model.noise.stddev(d[i], out.model.bias), 1e-4);
      problem.AddResidualBlock(beamCost(config.order, r.angle_rad, r.y_m, 1.0 / s), nullptr, poses[r.stop].data(),
                               centres.at(r.landmark).data(), &radius, alpha.data());
    }
    for (std::size_t k2 = 0; k2 < poses.size(); ++k2) {
      const Pose2& c = obs.commanded[k2];
      const double yaw = poses[k2][2] + wrapAngle(c.yaw_rad - poses[k2][2]);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PosePriorCost, 3, 3>(new PosePriorCost{
                                   c.x_m, c.y_m, yaw, 1.0 / config.sigma_s_m, 1.0 / config.sigma_psi_rad}),
                               nullptr, poses[k2].data());
    }
    if (!config.estimate_radius && problem.HasParameterBlock(&radius)) problem.SetParameterBlockConstant(&radius);
    ceres::Covariance::Options copt;
    copt.algorithm_type = ceres::DENSE_SVD;
    copt.null_space_rank = -1;
    ceres::Covariance cov(copt);
    std::vector<std::pair<const double*, const double*>> blocks = {{alpha.data(), alpha.data()}};
    for (auto& [id, c] : centres)
      if (problem.HasParameterBlock(c.data())) blocks.emplace_back(c.data(), c.data());
    if (problem.HasParameterBlock(alpha.data()) && cov.Compute(blocks, &problem)) {
      const int n = config.order + 1;
      out.alpha_covariance.resize(n, n);
      cov.GetCovarianceBlock(alpha.data(), alpha.data(), out.alpha_covariance.data());
      for (auto& [id, c] : centres) {
        if (!problem.HasParameterBlock(c.data())) continue;
        Eigen::Matrix2d m;
        cov.GetCovarianceBlock(c.data(), c.data(), m.data());
        out.centre_covariance[id] = m;
      }
    }
  }
  return out;
}

}  // namespace lidarcal::calibration
