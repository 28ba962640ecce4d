// SPDX-License-Identifier: BSD-3-Clause
#include "noise/ml.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <ceres/ceres.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "common/errors.hpp"
#include "noise/ml_model.hpp"

namespace lidarcal::noise {

using ml::AdjustmentAnalysis;
using ml::analyseAdjustment;
using ml::groupNames;
using ml::linearizeObservation;
using ml::linearizeOdometry;
using ml::ObservationCost;
using ml::ObservationLinear;
using ml::OdometryCost;
using ml::OdometryLinear;

void MlNoiseConfig::validate() const {
  if (max_iterations < 1) throw InputError("", "max_iterations", "must be at least 1");
  if (!(tolerance > 0.0)) throw InputError("", "tolerance", "must be positive");
  if (!(min_variance > 0.0)) throw InputError("", "min_variance", "must be positive");
  if (solver_iterations < 1) throw InputError("", "solver_iterations", "must be at least 1");
  if (max_motions_for_information < 0)
    throw InputError("", "max_motions_for_information", "must be at least 0");
  for (const auto& s : initial.sensors)
    if (!(s.range_var_m2 > 0.0) || !(s.bearing_var_rad2 > 0.0))
      throw InputError("", "initial noise", "sensor variances must be positive");
}

MlState initialState(const NoiseProblem& problem) {
  MlState st;
  st.poses.push_back(Pose2{});
  for (int k = 1; k < problem.stops; ++k) {
    const OdometryStep& u = problem.odometry[static_cast<std::size_t>(k)];
    // dead reckoning
    st.poses.push_back(compose(st.poses.back(), Pose2{u.dx_m, u.dy_m, u.dtheta_rad}));
  }
  st.landmarks.assign(static_cast<std::size_t>(problem.landmarks), {0.0, 0.0});
  std::vector<int> count(static_cast<std::size_t>(problem.landmarks), 0);
  for (const auto& o : problem.observations) {
    const Pose2& p = st.poses[static_cast<std::size_t>(o.stop)];
    double wx = 0.0, wy = 0.0;
    p.toWorld(o.range_m * std::cos(o.bearing_rad), o.range_m * std::sin(o.bearing_rad), wx, wy);
    auto& lm = st.landmarks[static_cast<std::size_t>(o.landmark)];
    lm[0] += wx;
    lm[1] += wy;
    ++count[static_cast<std::size_t>(o.landmark)];
  }
  for (std::size_t j = 0; j < st.landmarks.size(); ++j) {
    st.landmarks[j][0] /= count[j];
    st.landmarks[j][1] /= count[j];
  }
  st.biases.assign(static_cast<std::size_t>(problem.sensors), {0.0, 0.0});
  return st;
}

std::vector<double> residualsAt(const NoiseProblem& problem, const MlState& state,
                                std::vector<int>* group) {
  std::vector<double> r;
  if (group) group->clear();
  const int S = problem.sensors;
  for (const auto& o : problem.observations) {
    ObservationLinear lin;
    linearizeObservation(state.poses[static_cast<std::size_t>(o.stop)],
                         state.landmarks[static_cast<std::size_t>(o.landmark)].data(),
                         state.biases[static_cast<std::size_t>(o.sensor)].data(), o, lin);
    for (int c = 0; c < 2; ++c) {
      r.push_back(lin.res[c]);
      if (group) group->push_back(2 * o.sensor + c);
    }
  }
  for (int k = 1; k < problem.stops; ++k) {
    OdometryLinear lin;
    linearizeOdometry(state.poses[static_cast<std::size_t>(k - 1)],
                      state.poses[static_cast<std::size_t>(k)],
                      problem.odometry[static_cast<std::size_t>(k)], lin);
    for (int c = 0; c < 3; ++c) {
      r.push_back(lin.res[c]);
      if (group) group->push_back(2 * S + c);
    }
  }
  return r;
}

namespace {

/// Checks the configuration against the data: sensor count, translation for the biases.
void checkData(const NoiseProblem& problem, const MlNoiseConfig& config) {
  const int S = problem.sensors;
  if (!config.initial.sensors.empty() && static_cast<int>(config.initial.sensors.size()) != S)
    throw InputError("", "initial noise",
                     "lists " + std::to_string(config.initial.sensors.size()) +
                         " sensors, the data " + std::to_string(S));
  if (config.estimate_biases) {
    double travel = 0.0;
    for (const auto& u : problem.odometry) travel += std::hypot(u.dx_m, u.dy_m);
    if (!(travel > 0.0))
      throw DataError("odometry", "", "has no translation: sensor biases are not identifiable",
                      "estimate without biases, or record while the robot moves");
  }
}

/// Variances: the initial setting, or 1 (m^2, rad^2) for the sensors and 0.01 for the process:
/// readings start under-weighted against the odometry, which keeps the first adjustment near
/// dead reckoning (over-weighted bearings can pull a landmark onto a pose); zeros start at 0.01.
std::vector<double> initialVariances(int S, const MlNoiseConfig& config) {
  std::vector<double> var(static_cast<std::size_t>(2 * S + 3), 1.0);
  for (int c = 0; c < 3; ++c) var[static_cast<std::size_t>(2 * S + c)] = 0.01;
  if (!config.initial.sensors.empty())
    for (int s = 0; s < S; ++s) {
      var[static_cast<std::size_t>(2 * s)] =
          config.initial.sensors[static_cast<std::size_t>(s)].range_var_m2;
      var[static_cast<std::size_t>(2 * s + 1)] =
          config.initial.sensors[static_cast<std::size_t>(s)].bearing_var_rad2;
    }
  const ProcessNoise& q0 = config.initial.process;
  const double q0v[3] = {q0.dx_var_m2, q0.dy_var_m2, q0.dtheta_var_rad2};
  for (int c = 0; c < 3; ++c) {
    double v = q0v[c];
    if (config.estimate_process && !(v > 0.0)) v = 0.01;
    var[static_cast<std::size_t>(2 * S + c)] = std::max(v, config.min_variance);
  }
  return var;
}

ceres::Solver::Options solverOptions(const MlNoiseConfig& config) {
  ceres::Solver::Options sopts;
  sopts.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  sopts.max_num_iterations = config.solver_iterations;
  sopts.num_threads = 1;
  sopts.logging_type = ceres::SILENT;
  sopts.minimizer_progress_to_stdout = false;
  sopts.function_tolerance = 1e-10;
  sopts.gradient_tolerance = 1e-10;
  sopts.parameter_tolerance = 1e-10;
  return sopts;
}

ceres::Problem::Options problemOptions() {
  ceres::Problem::Options popts;
  popts.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  return popts;
}

/// Iterated variance-component estimation (the steps of ml.hpp): the weighted adjustment
/// (Ceres, whitened by the current variances), then per group the Foerstner update as a
/// scoring step, until the variances settle; then the standard errors.
class VceEstimator {
 public:
  VceEstimator(const NoiseProblem& problem, const MlNoiseConfig& config);
  MlNoiseResult run();

 private:
  /// A process variance is held at its start when the process noise is given.
  bool fixedGroup(int g) const { return g >= 2 * S_ && !config_.estimate_process; }
  void setWeights();
  void buildAdjustment();
  void solve(bool wrap_yaw);
  void checkLandmarksOffRobot() const;
  bool updateVariances();
  double updatedVariance(int g, double r, double r2, double omega);
  void fillNoise();
  void standardErrors(const AdjustmentAnalysis& an);

  const NoiseProblem& problem_;
  const MlNoiseConfig& config_;
  const int S_, K_, G_;
  std::vector<double> var_;        // current variances, order of the groups
  std::vector<double> inv_sigma_;  // 1 / sqrt(var), read by the cost functions
  MlNoiseResult result_;
  std::vector<std::array<double, 3>> pose_blocks_;  // Ceres parameter blocks of the poses
  ceres::Problem cp_;
  const ceres::Solver::Options sopts_;
  const std::vector<std::string> names_;
  std::vector<double> acceleration_, last_step_;  // per group: scoring step factor, last step
};

VceEstimator::VceEstimator(const NoiseProblem& problem, const MlNoiseConfig& config)
    : problem_(problem),
      config_(config),
      S_(problem.sensors),
      K_(problem.stops),
      G_(2 * S_ + 3),
      var_(initialVariances(S_, config)),
      inv_sigma_(static_cast<std::size_t>(G_)),
      pose_blocks_(static_cast<std::size_t>(K_)),
      cp_(problemOptions()),
      sopts_(solverOptions(config)),
      names_(groupNames(S_)),
      acceleration_(static_cast<std::size_t>(G_), 1.0),
      last_step_(static_cast<std::size_t>(G_), 0.0) {}

void VceEstimator::setWeights() {
  for (int g = 0; g < G_; ++g)
    inv_sigma_[static_cast<std::size_t>(g)] = 1.0 / std::sqrt(var_[static_cast<std::size_t>(g)]);
}

void VceEstimator::buildAdjustment() {
  result_.state = initialState(problem_);
  MlState& st = result_.state;
  for (int k = 0; k < K_; ++k) {
    const Pose2& p = st.poses[static_cast<std::size_t>(k)];
    pose_blocks_[static_cast<std::size_t>(k)] = {p.x_m, p.y_m, p.yaw_rad};
  }
  for (const auto& o : problem_.observations) {
    const double* w = &inv_sigma_[static_cast<std::size_t>(2 * o.sensor)];
    double* lm = st.landmarks[static_cast<std::size_t>(o.landmark)].data();
    double* bias = st.biases[static_cast<std::size_t>(o.sensor)].data();
    if (o.stop == 0)
      cp_.AddResidualBlock(new ObservationCost(o, false, w), nullptr, lm, bias);
    else
      cp_.AddResidualBlock(new ObservationCost(o, true, w), nullptr,
                           pose_blocks_[static_cast<std::size_t>(o.stop)].data(), lm, bias);
  }
  for (int k = 1; k < K_; ++k) {
    const double* w = &inv_sigma_[static_cast<std::size_t>(2 * S_)];
    const OdometryStep& u = problem_.odometry[static_cast<std::size_t>(k)];
    if (k == 1)
      cp_.AddResidualBlock(new OdometryCost(u, true, w), nullptr, pose_blocks_[1].data());
    else
      cp_.AddResidualBlock(new OdometryCost(u, false, w), nullptr,
                           pose_blocks_[static_cast<std::size_t>(k - 1)].data(),
                           pose_blocks_[static_cast<std::size_t>(k)].data());
  }
  if (!config_.estimate_biases)
    for (auto& b : st.biases) cp_.SetParameterBlockConstant(b.data());
}

/// One weighted adjustment; the poses copied back (yaw wrapped for the final one).
void VceEstimator::solve(bool wrap_yaw) {
  ceres::Solver::Summary summary;
  ceres::Solve(sopts_, &cp_, &summary);
  result_.solver_iterations += static_cast<int>(summary.iterations.size());
  for (int k = 0; k < K_; ++k) {
    const auto& b = pose_blocks_[static_cast<std::size_t>(k)];
    result_.state.poses[static_cast<std::size_t>(k)] =
        Pose2{b[0], b[1], wrap_yaw ? wrapAngle(b[2]) : b[2]};
  }
}

/// A landmark on top of a pose has no bearing and a singular Jacobian: the data hold a
/// reading at (nearly) zero range, which the Gaussian model cannot explain.
void VceEstimator::checkLandmarksOffRobot() const {
  const MlState& st = result_.state;
  for (const auto& o : problem_.observations) {
    const auto& l = st.landmarks[static_cast<std::size_t>(o.landmark)];
    const Pose2& p = st.poses[static_cast<std::size_t>(o.stop)];
    if (std::hypot(l[0] - p.x_m, l[1] - p.y_m) < 1e-4)
      throw DataError(
          "observations",
          "stop " + std::to_string(o.stop) + ", landmark " +
              std::to_string(problem_.landmark_ids[static_cast<std::size_t>(o.landmark)]),
          "the adjustment put the landmark on the robot (reading range " +
              std::to_string(o.range_m) + " m)",
          "leave out readings at ranges the sensor cannot measure (below its minimum range)");
  }
}

/// Foerstner's update var <- Omega / r is a fixed-point step of the REML score
/// (Omega / var - r) / (2 var) = 0; scaling it by the diagonal Fisher information
/// sum r_ii^2 / (2 var^2) gives a scoring step that reaches a component near zero in a
/// few iterations instead of ~1/n. Safeguard: at most a factor 10 per iteration.
/// The diagonal information ignores correlations between residuals, so the step can
/// overshoot: the extra factor is halved each time the step changes sign.
double VceEstimator::updatedVariance(int g, double r, double r2, double omega) {
  const auto ug = static_cast<std::size_t>(g);
  const double em_step = omega / r - var_[ug];
  if (em_step * last_step_[ug] < 0.0) acceleration_[ug] *= 0.5;
  const double factor = 1.0 + acceleration_[ug] * (r * r / r2 / r - 1.0);
  const double ratio = std::clamp((var_[ug] + factor * em_step) / var_[ug], 0.1, 10.0);
  last_step_[ug] = em_step;
  return std::max(var_[ug] * ratio, config_.min_variance);
}

/// Variance components from the residuals and the redundancy numbers; true when converged.
bool VceEstimator::updateVariances() {
  std::vector<int> group_of;
  const std::vector<double> res = residualsAt(problem_, result_.state, &group_of);
  std::vector<double> omega(static_cast<std::size_t>(G_), 0.0);
  std::vector<std::size_t> count(static_cast<std::size_t>(G_), 0);
  for (std::size_t i = 0; i < res.size(); ++i) {
    omega[static_cast<std::size_t>(group_of[i])] += res[i] * res[i];
    ++count[static_cast<std::size_t>(group_of[i])];
  }
  const AdjustmentAnalysis an =
      analyseAdjustment(problem_, result_.state, var_, config_.estimate_biases);
  // Restricted (REML) negative log-likelihood of the linearised model, constants dropped:
  //   1/2 [ sum_g n_g log var_g + sum_g Omega_g / var_g + log det N ].
  double nll = 0.5 * an.log_det_normal;
  bool converged = true;
  for (int g = 0; g < G_; ++g) {
    const auto ug = static_cast<std::size_t>(g);
    MlGroup& grp = result_.groups[ug];
    grp.name = names_[ug];
    grp.count = count[ug];
    grp.redundancy = an.redundancy[ug];
    grp.sum_sq = omega[ug];
    if (count[ug] > 0)
      nll += 0.5 * (omega[ug] / var_[ug] + static_cast<double>(count[ug]) * std::log(var_[ug]));
    const double r = an.redundancy[ug], r2 = an.redundancy_sq[ug];
    double updated = var_[ug];
    if (!fixedGroup(g) && count[ug] > 0 && r > 1e-12 && r2 > 1e-24)
      updated = updatedVariance(g, r, r2, omega[ug]);
    const double se = updated * std::sqrt(2.0 / std::max(r2, 1e-24));
    // Converged when the change is small against the variance or, for components near zero,
    // against their standard error (the likelihood is flat there).
    if (std::abs(updated - var_[ug]) > config_.tolerance * std::max(updated, se)) converged = false;
    grp.variance = updated;
    grp.standard_error = se;
    grp.at_floor = updated <= config_.min_variance;
    var_[ug] = updated;
  }
  result_.objective_trace.push_back(nll);
  result_.variance_trace.push_back(var_);
  return converged;
}

void VceEstimator::fillNoise() {
  const MlState& st = result_.state;
  result_.noise.sensors.resize(static_cast<std::size_t>(S_));
  for (int s = 0; s < S_; ++s) {
    SensorNoise& n = result_.noise.sensors[static_cast<std::size_t>(s)];
    n.range_mean_m = st.biases[static_cast<std::size_t>(s)][0];
    n.bearing_mean_rad = st.biases[static_cast<std::size_t>(s)][1];
    n.range_var_m2 = var_[static_cast<std::size_t>(2 * s)];
    n.bearing_var_rad2 = var_[static_cast<std::size_t>(2 * s + 1)];
  }
  result_.noise.process.dx_var_m2 = var_[static_cast<std::size_t>(2 * S_)];
  result_.noise.process.dy_var_m2 = var_[static_cast<std::size_t>(2 * S_ + 1)];
  result_.noise.process.dtheta_var_rad2 = var_[static_cast<std::size_t>(2 * S_ + 2)];
}

/// Standard errors from the inverse information over the variances that were estimated and
/// are away from the floor (fixed ones and those at the floor are held as known).
void VceEstimator::standardErrors(const AdjustmentAnalysis& an) {
  std::vector<int> free;
  for (int g = 0; g < G_; ++g) {
    const MlGroup& grp = result_.groups[static_cast<std::size_t>(g)];
    if (!fixedGroup(g) && grp.count > 0 && !grp.at_floor) free.push_back(g);
  }
  const auto n_free = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd info(n_free, n_free);
  for (Eigen::Index a = 0; a < n_free; ++a)
    for (Eigen::Index b = 0; b < n_free; ++b)
      info(a, b) = an.fisher(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]);
  Eigen::LLT<Eigen::MatrixXd> llt(info);
  if (n_free > 0 && llt.info() == Eigen::Success) {
    const Eigen::MatrixXd cov = llt.solve(Eigen::MatrixXd::Identity(n_free, n_free));
    for (Eigen::Index a = 0; a < n_free; ++a)
      result_.groups[static_cast<std::size_t>(free[static_cast<std::size_t>(a)])].standard_error =
          std::sqrt(cov(a, a));
    result_.standard_error_method = "information";
  }
}

MlNoiseResult VceEstimator::run() {
  setWeights();
  buildAdjustment();
  result_.groups.resize(static_cast<std::size_t>(G_));
  for (int it = 0; it < config_.max_iterations; ++it) {
    setWeights();
    solve(false);
    ++result_.iterations;
    checkLandmarksOffRobot();
    if (updateVariances()) {
      result_.converged = true;
      break;
    }
  }
  if (!result_.converged)
    result_.message =
        "variances still changing after " + std::to_string(config_.max_iterations) + " iterations";
  // Final solve at the final variances so poses, landmarks and biases match them.
  setWeights();
  solve(true);
  fillNoise();
  const bool full_information = K_ - 1 <= config_.max_motions_for_information;
  const AdjustmentAnalysis an =
      analyseAdjustment(problem_, result_.state, var_, config_.estimate_biases, full_information);
  result_.bias_standard_error = an.bias_std;
  if (full_information) standardErrors(an);
  return std::move(result_);
}

}  // namespace

MlNoiseResult estimateNoiseMl(const NoiseProblem& problem, const MlNoiseConfig& config) {
  config.validate();
  checkData(problem, config);
  return VceEstimator(problem, config).run();
}

}  // namespace lidarcal::noise
