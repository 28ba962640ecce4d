// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/rig_problem.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>
#include <tuple>

#include "calibration/joint_costs.hpp"
#include "calibration/rig_start.hpp"

namespace lidarcal::calibration::rig {
namespace {

/// Residual of one pooled beam: (mean reading - f_s(d)) / sqrt(variance), d along the beam from
/// the sensor's pose T_k M_s to the pole's circle (rig_calibrate.hpp). N = order + 1.
template <int N>
struct RigBeamCost {
  double angle_rad, flip, mean_m, inv_sd;
  template <typename T>
  bool operator()(const T* v, const T* m, const T* c, const T* r, const T* alpha,
                  T* residual) const {
    using std::cos;
    using std::sin;
    const T cv = cos(v[2]), sv = sin(v[2]);
    const T px = v[0] + cv * m[0] - sv * m[1];
    const T py = v[1] + sv * m[0] + cv * m[1];
    const T a = v[2] + m[2] + T(flip * angle_rad);
    const T d = rayCircleDistance(px, py, a, c[0], c[1], r[0]);
    residual[0] = (T(mean_m) - evaluatePolynomial<N>(alpha, d)) * T(inv_sd);
    return true;
  }
};

template <int N>
ceres::CostFunction* makeCost(const RigBeamCost<N>& c) {
  return new ceres::AutoDiffCostFunction<RigBeamCost<N>, 1, 3, 3, 2, 1, N>(new RigBeamCost<N>(c));
}

ceres::CostFunction* beamCost(int order, double angle, double flip, double mean, double inv_sd) {
  switch (order) {
    case 1:
      return makeCost<2>({angle, flip, mean, inv_sd});
    case 2:
      return makeCost<3>({angle, flip, mean, inv_sd});
    case 3:
      return makeCost<4>({angle, flip, mean, inv_sd});
    case 4:
      return makeCost<5>({angle, flip, mean, inv_sd});
    default:
      throw std::invalid_argument("rig calibration: bias order must be 1..4");
  }
}

ceres::Solver::Options solverOptions(int max_iterations) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = max_iterations;
  options.function_tolerance = 1e-12;
  options.parameter_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  return options;
}

/// The sensor's pose in the world: the vehicle's pose followed by the mounting.
Pose2 sensorPose(const double* v, const double* m) {
  return compose(Pose2{v[0], v[1], v[2]}, Pose2{m[0], m[1], m[2]});
}

}  // namespace

RigProblem::RigProblem(const RigObservations& obs, const RigConfig& config, const FitSetup& setup)
    : obs_(obs), config_(config), setup_(setup) {
  const std::size_t S = obs.sensors.size();
  if (setup.orders.size() != S || setup.flips.size() != S ||
      setup.stop_held.size() != obs.vehicle.size())
    throw std::invalid_argument(
        "RigProblem: one order and flip per sensor and one hold flag per stop needed");
  out_.frame = setup.frame;
  out_.reference = config.reference;
  out_.motion_prior = setup.motion;
  out_.scale_free = setup.scale_held;
  poolBeams();
  initialiseParameters();
  initialisePoles();
}

std::size_t RigProblem::poleIndex(int id) const {
  return static_cast<std::size_t>(std::lower_bound(pole_ids_.begin(), pole_ids_.end(), id) -
                                  pole_ids_.begin());
}

/// One pooled beam per (sensor, stop, pole, beam index); a beam without an index is its own.
void RigProblem::poolBeams() {
  std::map<std::tuple<std::size_t, std::size_t, int, std::uint32_t>, std::size_t> index;
  struct Sum {
    double n = 0, sum = 0, sumsq = 0;
  };
  std::vector<Sum> sums;
  readings_per_sensor_.assign(obs_.sensors.size(), 0);
  for (const RigSighting& s : obs_.sightings) {
    if (s.sensor >= obs_.sensors.size() || s.stop >= obs_.vehicle.size())
      throw std::invalid_argument(
          "RigProblem: a sighting names a sensor or stop that does not exist");
    for (const BeamReading& b : s.beams) {
      if (!std::isfinite(b.range_m) || b.beside) continue;
      std::size_t at = beams_.size();
      bool fresh = true;
      if (b.beam != kUnknownBeam) {
        const auto inserted =
            index.emplace(std::make_tuple(s.sensor, s.stop, s.pole, b.beam), beams_.size());
        at = inserted.first->second;
        fresh = inserted.second;
      }
      if (fresh) {
        beams_.push_back(PooledBeam{s.sensor, s.stop, s.pole, b.angle_rad, 0.0, 0.0, 0.0});
        sums.emplace_back();
      }
      Sum& sum = sums[at];
      sum.n += 1.0;
      sum.sum += b.range_m;
      sum.sumsq += b.range_m * b.range_m;
      ++readings_per_sensor_[s.sensor];
    }
  }
  for (std::size_t i = 0; i < beams_.size(); ++i) {
    beams_[i].n = sums[i].n;
    beams_[i].mean_m = sums[i].sum / sums[i].n;
    beams_[i].within_ss =
        std::max(0.0, sums[i].sumsq - sums[i].n * beams_[i].mean_m * beams_[i].mean_m);
  }
  for (const RigSighting& s : obs_.sightings) pole_ids_.push_back(s.pole);
  std::sort(pole_ids_.begin(), pole_ids_.end());
  pole_ids_.erase(std::unique(pole_ids_.begin(), pole_ids_.end()), pole_ids_.end());
}

void RigProblem::initialiseParameters() {
  const std::size_t K = obs_.vehicle.size(), S = obs_.sensors.size();
  mount_offset_ = 3 * K;
  pole_offset_ = mount_offset_ + 3 * S;
  radius_offset_ = pole_offset_ + 2 * pole_ids_.size();
  std::size_t next = radius_offset_ + 1;
  for (std::size_t s = 0; s < S; ++s) {
    alpha_offset_.push_back(next);
    next += static_cast<std::size_t>(setup_.orders[s]) + 1;
  }
  params_.assign(next, 0.0);
  for (std::size_t k = 0; k < K; ++k) {
    const Pose2& p = obs_.vehicle[k];
    std::copy_n(std::array<double, 3>{p.x_m, p.y_m, p.yaw_rad}.data(), 3, vehicle(k));
  }
  for (std::size_t s = 0; s < S; ++s) {
    const Mounting& m = obs_.sensors[s].prior;
    std::copy_n(std::array<double, 3>{m.x_m, m.y_m, m.yaw_rad}.data(), 3, mount(s));
    alpha(s)[1] = 1.0;  // f(d) = d
  }
  *radius() = obs_.pole_radius_m.value_or(0.05);
  // Each sensor's noise to start from: its scatter within the beams (free of the geometry), or 1
  // cm.
  std::vector<std::vector<NoiseSample>> samples(S);
  for (const PooledBeam& b : beams_)
    samples[b.sensor].push_back(NoiseSample{b.mean_m, b.n, b.within_ss, 0.0, 0.0});
  noise_.resize(S);
  for (std::size_t s = 0; s < S; ++s) {
    noise_[s] = fitSensorNoise(samples[s], config_.noise_kinds);
    if (!noise_[s].from_repeats) noise_[s].law = NoiseModel{NoiseKind::constant, {}, 0.01, 2.0};
    noise_[s].tau_m = 0.0;
  }
}

/// The starting mountings and poles (rig_start.hpp): the reference's poles, the others aligned to
/// them.
void RigProblem::initialisePoles() {
  std::vector<Pose2> mountings;
  for (std::size_t s = 0; s < obs_.sensors.size(); ++s)
    mountings.push_back(Pose2{mount(s)[0], mount(s)[1], mount(s)[2]});
  std::map<int, Eigen::Vector2d> centres;
  startingGeometry(obs_, setup_.flips, *radius(), config_.reference, mountings, centres);
  for (std::size_t s = 0; s < obs_.sensors.size(); ++s) {
    // held at its prior
    if (setup_.frame == RigFrame::relative && s == config_.reference) continue;
    std::copy_n(
        std::array<double, 3>{mountings[s].x_m, mountings[s].y_m, mountings[s].yaw_rad}.data(), 3,
        mount(s));
  }
  for (std::size_t i = 0; i < pole_ids_.size(); ++i) {
    const auto it = centres.find(pole_ids_[i]);
    if (it == centres.end()) continue;
    pole(i)[0] = it->second.x();
    pole(i)[1] = it->second.y();
  }
}

double RigProblem::distanceOf(const PooledBeam& b, double* lateral) const {
  const double* v = &params_[3 * b.stop];
  const double* m = &params_[mount_offset_ + 3 * b.sensor];
  const double* c = &params_[pole_offset_ + 2 * poleIndex(b.pole)];
  const double r = params_[radius_offset_];
  const Pose2 p = sensorPose(v, m);
  const double a = p.yaw_rad + setup_.flips[b.sensor] * b.angle_rad;
  if (lateral) *lateral = ((c[1] - p.y_m) * std::cos(a) - (c[0] - p.x_m) * std::sin(a)) / r;
  return rayCircleDistance(p.x_m, p.y_m, a, c[0], c[1], r);
}

double RigProblem::biasOf(std::size_t sensor, double d) const {
  const double* a = alpha(sensor);
  double f = 0.0;
  for (int k = setup_.orders[sensor]; k >= 0; --k) f = f * d + a[k];
  return f;
}

/// The beams that pass within lateral_fraction of the radius from their pole's centre now, or
/// (`all`, the first solve: the designed mountings may put a pole a radius off) every beam.
void RigProblem::selectBeams(bool all) {
  used_.clear();
  if (!all && setup_.selection) {
    used_ = *setup_.selection;
    leverage_.assign(used_.size(), 0.0);
    return;
  }
  for (std::size_t i = 0; i < beams_.size(); ++i) {
    double lateral = 0.0;
    distanceOf(beams_[i], &lateral);
    if (all || std::abs(lateral) <= config_.lateral_fraction) used_.push_back(i);
  }
  leverage_.assign(used_.size(), 0.0);
}

std::vector<std::vector<NoiseSample>> RigProblem::noiseSamples() const {
  std::vector<std::vector<NoiseSample>> samples(obs_.sensors.size());
  for (std::size_t j = 0; j < used_.size(); ++j) {
    const PooledBeam& b = beams_[used_[j]];
    const double f = biasOf(b.sensor, distanceOf(b, nullptr));
    samples[b.sensor].push_back(NoiseSample{f, b.n, b.within_ss, b.mean_m - f, leverage_[j]});
  }
  return samples;
}

void RigProblem::addResiduals(ceres::Problem& problem, bool robust,
                              std::vector<ceres::ResidualBlockId>* data_blocks) {
  for (std::size_t j = 0; j < used_.size(); ++j) {
    const PooledBeam& b = beams_[used_[j]];
    const double f = biasOf(b.sensor, distanceOf(b, nullptr));
    const double var = meanVariance(noise_[b.sensor], NoiseSample{f, b.n, 0.0, 0.0, 0.0});
    ceres::LossFunction* loss = robust ? new ceres::HuberLoss(2.0) : nullptr;
    const ceres::ResidualBlockId id = problem.AddResidualBlock(
        beamCost(setup_.orders[b.sensor], b.angle_rad, setup_.flips[b.sensor], b.mean_m,
                 1.0 / std::sqrt(var)),
        loss, vehicle(b.stop), mount(b.sensor), pole(poleIndex(b.pole)), radius(), alpha(b.sensor));
    if (data_blocks) data_blocks->push_back(id);
  }
}

/// Recorded poses as measurements of the vehicle: a prior per stop (stop and go, Alhashimi et
/// al. 2021 eq. 8), or the first stop's pose and every odometry step (a vehicle that never stops).
void RigProblem::addVehiclePriors(ceres::Problem& problem) {
  if (!obs_.vehicle_known) return;
  const double inv_s = 1.0 / config_.sigma_vehicle_m, inv_psi = 1.0 / config_.sigma_vehicle_rad;
  for (std::size_t k = 0; k < obs_.vehicle.size(); ++k) {
    if (!problem.HasParameterBlock(vehicle(k))) continue;
    const Pose2& p = obs_.vehicle[k];
    if (!setup_.motion || k == 0) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<joint::PosePriorCost, 3, 3>(
              new joint::PosePriorCost{p.x_m, p.y_m, p.yaw_rad, inv_s, inv_psi}),
          nullptr, vehicle(k));
      continue;
    }
    if (!problem.HasParameterBlock(vehicle(k - 1))) continue;
    const Pose2 step = stepBetween(obs_.vehicle[k - 1], p);
    const double len = motionStepLength(obs_.vehicle, k);
    const double st = config_.motion_sigma_fraction * len + config_.motion_sigma_floor_m;
    const double sp =
        config_.motion_heading_sigma_rad_per_m * len + config_.motion_heading_floor_rad;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<joint::MotionPriorCost, 3, 3, 3, 1>(
            new joint::MotionPriorCost{step.x_m, step.y_m, step.yaw_rad, 1.0 / st, 1.0 / sp}),
        nullptr, vehicle(k - 1), vehicle(k), &zero_scale_);
    problem.SetParameterBlockConstant(&zero_scale_);
  }
}

/// The gauge: the reference's mounting (relative frame), stops without recorded poses, the
/// range scale, and a radius that is given.
void RigProblem::holdGauge(ceres::Problem& problem) {
  const std::size_t ref = config_.reference;
  if (setup_.frame == RigFrame::relative && problem.HasParameterBlock(mount(ref)))
    problem.SetParameterBlockConstant(mount(ref));
  for (std::size_t k = 0; k < obs_.vehicle.size(); ++k)
    if (setup_.stop_held[k] && problem.HasParameterBlock(vehicle(k)))
      problem.SetParameterBlockConstant(vehicle(k));
  if (setup_.scale_held && problem.HasParameterBlock(alpha(ref)))
    problem.SetManifold(alpha(ref), new ceres::SubsetManifold(setup_.orders[ref] + 1, {1}));
  if (!problem.HasParameterBlock(radius())) return;
  if (obs_.pole_radius_m)
    problem.SetParameterBlockConstant(radius());
  else
    problem.SetParameterLowerBound(radius(), 0, 1e-3);
}

bool RigProblem::solve(bool hold_bias, bool robust) {
  ceres::Problem problem;
  addResiduals(problem, robust, nullptr);
  addVehiclePriors(problem);
  holdGauge(problem);
  if (hold_bias)
    for (std::size_t s = 0; s < obs_.sensors.size(); ++s)
      if (problem.HasParameterBlock(alpha(s))) problem.SetParameterBlockConstant(alpha(s));
  ceres::Solver::Summary summary;
  ceres::Solve(solverOptions(config_.max_solver_iterations), &problem, &summary);
  out_.solver_iterations += static_cast<int>(summary.iterations.size());
  if (!summary.IsSolutionUsable()) {
    out_.status =
        Status{StatusCode::solver_failed, "Ceres found no usable solution: " + summary.message};
    return false;
  }
  return true;
}

/// Each sensor's noise from its beams at the current estimate; true when every sigma_e and
/// tau moved by less than 1 %.
bool RigProblem::reestimateNoise() {
  const auto samples = noiseSamples();
  bool settled = true;
  for (std::size_t s = 0; s < noise_.size(); ++s) {
    if (samples[s].empty()) continue;
    const SensorNoise before = noise_[s];
    noise_[s] = fitSensorNoise(samples[s], config_.noise_kinds);
    const auto moved = [](double a, double b) {
      return std::abs(a - b) > 0.01 * std::max(std::abs(b), 1e-6);
    };
    settled = settled && before.law.kind == noise_[s].law.kind &&
              !moved(noise_[s].law.sigma_e, before.law.sigma_e) &&
              !moved(noise_[s].tau_m, before.tau_m);
  }
  return settled;
}

RigResult RigProblem::run() {
  selectBeams(true);
  if (used_.empty()) {
    out_.status = Status{StatusCode::too_few_readings, "no beam reading falls on a pole"};
    return out_;
  }
  if (!solve(true, true)) return out_;  // the geometry first, the bias held at f(d) = d
  for (int outer = 1; outer <= config_.outer_iterations; ++outer) {
    selectBeams(false);
    const bool settled = reestimateNoise();
    if (!solve(false, true)) return out_;
    if (settled && outer >= 2) break;
  }
  // The noise once more with the fitted parameters' share of each residual taken out, then the
  // maximum-likelihood solve (no robust loss: the likelihood compared between orders) and its
  // covariance.
  for (int pass = 0; pass < 2; ++pass) {
    if (!computeCovariance()) return out_;
    reestimateNoise();
    if (!solve(false, false)) return out_;
  }
  if (!computeCovariance()) return out_;
  summarise();
  return out_;
}

}  // namespace lidarcal::calibration::rig
