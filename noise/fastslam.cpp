// SPDX-License-Identifier: BSD-3-Clause
#include "noise/fastslam.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <Eigen/Dense>

#include "common/errors.hpp"
#include "common/rng.hpp"

namespace lidarcal::noise {
namespace {

struct LandmarkEkf {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  bool seen = false;
};

struct Particle {
  Pose2 pose;
  std::vector<LandmarkEkf> map;
};

Pose2 compose(const Pose2& pose, double dx, double dy, double dtheta) {
  Pose2 out;
  pose.toWorld(dx, dy, out.x_m, out.y_m);
  out.yaw_rad = wrapAngle(pose.yaw_rad + dtheta);
  return out;
}

// Predicted errors of one observation against one particle: reading minus h(pose, landmark)
// (Sharma 2020 ch. 3.2), without the assumed bias.
void predictedError(const Pose2& pose, const Eigen::Vector2d& lm, const Observation& o, double& er,
                    double& eb) {
  const double dx = lm.x() - pose.x_m, dy = lm.y() - pose.y_m;
  er = o.range_m - std::hypot(dx, dy);
  eb = wrapAngle(o.bearing_rad - (std::atan2(dy, dx) - pose.yaw_rad));
}

// Normalises weights in place; returns log of their sum before normalisation.
double normalise(std::vector<double>& w) {
  double sum = 0.0;
  for (double v : w) sum += v;
  if (!(sum > 0.0) || !std::isfinite(sum)) {
    std::fill(w.begin(), w.end(), 1.0 / static_cast<double>(w.size()));
    return -std::numeric_limits<double>::infinity();
  }
  for (double& v : w) v /= sum;
  return std::log(sum);
}

}  // namespace

void FastSlamConfig::validate() const {
  if (particles < 1 || particles > 1'000'000)
    throw InputError("", "particles", "must be between 1 and 1000000", "the seed uses 80");
  if (!(resample_fraction >= 0.0 && resample_fraction <= 1.0))
    throw InputError("", "resample_fraction", "must be in [0, 1]");
}

namespace {

void validateAssumed(const NoiseProblem& problem, const NoiseSetting& assumed) {
  if (static_cast<int>(assumed.sensors.size()) < problem.sensors)
    throw InputError("", "assumed noise",
                     "has " + std::to_string(assumed.sensors.size()) + " sensors, the data " +
                         std::to_string(problem.sensors));
  for (int s = 0; s < problem.sensors; ++s) {
    const SensorNoise& n = assumed.sensors[static_cast<std::size_t>(s)];
    if (!(n.range_var_m2 > 0.0) || !(n.bearing_var_rad2 > 0.0))
      throw InputError("", "assumed noise of sensor " + std::to_string(s),
                       "variances must be positive");
  }
}

/// The particle filter over one problem: per stop predict, update with each observation,
/// record the predicted errors and the mean pose, resample (Sharma 2020 ch. 3.1-3.2).
class FastSlamFilter {
 public:
  FastSlamFilter(const NoiseProblem& problem, const NoiseSetting& assumed,
                 const FastSlamConfig& config, std::uint64_t seed, std::uint64_t stream);
  FastSlamResult run();

 private:
  void predict(int k);
  bool update(const Observation& o);
  bool updateParticle(std::size_t pi, const Observation& o, const SensorNoise& n,
                      const Eigen::Matrix2d& R);
  void recordErrors(const Observation& o);
  void recordMeanPose();
  void resample();

  const NoiseProblem& problem_;
  const NoiseSetting& assumed_;
  const FastSlamConfig& config_;
  std::size_t n_particles_;
  std::vector<Particle> particles_, scratch_;
  std::vector<double> weight_, log_lik_;
  std::vector<char> initialised_;
  FastSlamResult result_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  double sq_dx_, sq_dy_, sq_dt_;  // process noise standard deviations
};

// Without process noise every particle follows the same path with the same map and weight:
// one particle gives the same result (up to rounding) at 1/N of the cost.
std::size_t particleCount(const ProcessNoise& q, const FastSlamConfig& config) {
  const bool deterministic = config.collapse_identical_particles && q.dx_var_m2 == 0.0 &&
                             q.dy_var_m2 == 0.0 && q.dtheta_var_rad2 == 0.0;
  return deterministic ? std::size_t{1} : static_cast<std::size_t>(config.particles);
}

FastSlamFilter::FastSlamFilter(const NoiseProblem& problem, const NoiseSetting& assumed,
                               const FastSlamConfig& config, std::uint64_t seed,
                               std::uint64_t stream)
    : problem_(problem),
      assumed_(assumed),
      config_(config),
      n_particles_(particleCount(assumed.process, config)),
      particles_(
          n_particles_,
          Particle{Pose2{}, std::vector<LandmarkEkf>(static_cast<std::size_t>(problem.landmarks))}),
      weight_(n_particles_, 1.0 / static_cast<double>(n_particles_)),
      log_lik_(n_particles_),
      initialised_(n_particles_),
      rng_(makeRng(seed, stream)),
      sq_dx_(std::sqrt(assumed.process.dx_var_m2)),
      sq_dy_(std::sqrt(assumed.process.dy_var_m2)),
      sq_dt_(std::sqrt(assumed.process.dtheta_var_rad2)) {
  result_.errors.resize(static_cast<std::size_t>(problem.sensors));
  result_.mean_trajectory.reserve(static_cast<std::size_t>(problem.stops));
}

FastSlamResult FastSlamFilter::run() {
  for (int k = 0; k < problem_.stops; ++k) {
    if (k > 0) predict(k);
    // Update: one EKF per particle and landmark, weights by the innovation likelihood.
    const std::size_t begin = problem_.stop_begin[static_cast<std::size_t>(k)];
    const std::size_t end = problem_.stop_begin[static_cast<std::size_t>(k) + 1];
    std::vector<char> used(end - begin, 1);
    for (std::size_t i = begin; i < end; ++i)
      if (update(problem_.observations[i]) && config_.skip_initialising) used[i - begin] = 0;
    // Predicted errors of this stop's observations against the updated particles (ch. 3.2).
    for (std::size_t i = begin; i < end; ++i)
      if (used[i - begin]) recordErrors(problem_.observations[i]);
    recordMeanPose();
    resample();
  }
  return std::move(result_);
}

/// Prediction (Sharma 2020 ch. 3.1): commanded motion plus sampled process noise.
void FastSlamFilter::predict(int k) {
  const OdometryStep& u = problem_.odometry[static_cast<std::size_t>(k)];
  for (auto& p : particles_) {
    const double n1 = normal_(rng_), n2 = normal_(rng_), n3 = normal_(rng_);
    p.pose =
        compose(p.pose, u.dx_m + sq_dx_ * n1, u.dy_m + sq_dy_ * n2, u.dtheta_rad + sq_dt_ * n3);
  }
}

/// Updates every particle with one observation; true when it initialised its landmark in all of
/// them.
bool FastSlamFilter::update(const Observation& o) {
  const SensorNoise& n = assumed_.sensors[static_cast<std::size_t>(o.sensor)];
  const Eigen::Matrix2d R = Eigen::Vector2d(n.range_var_m2, n.bearing_var_rad2).asDiagonal();
  bool any_update = false;
  for (std::size_t pi = 0; pi < n_particles_; ++pi)
    if (updateParticle(pi, o, n, R)) any_update = true;
  if (any_update) {
    // Weights times likelihoods, in the log domain against underflow.
    const double top = *std::max_element(log_lik_.begin(), log_lik_.end());
    for (std::size_t pi = 0; pi < n_particles_; ++pi) weight_[pi] *= std::exp(log_lik_[pi] - top);
    result_.log_evidence += top + normalise(weight_);
  }
  bool all_init = true;
  for (std::size_t pi = 0; pi < n_particles_; ++pi) all_init = all_init && initialised_[pi];
  return all_init;
}

/// One particle's landmark EKF: initialised from the inverse observation model when first
/// seen, else updated; true when updated (log_lik_ then holds the innovation's log-likelihood).
bool FastSlamFilter::updateParticle(std::size_t pi, const Observation& o, const SensorNoise& n,
                                    const Eigen::Matrix2d& R) {
  Particle& p = particles_[pi];
  LandmarkEkf& lm = p.map[static_cast<std::size_t>(o.landmark)];
  initialised_[pi] = 0;
  log_lik_[pi] = 0.0;  // log-likelihood; 0 for particles not updated
  if (!lm.seen) {
    // Inverse observation model with the assumed bias removed; covariance G R G^T.
    const double r = o.range_m - n.range_mean_m;
    const double a = p.pose.yaw_rad + o.bearing_rad - n.bearing_mean_rad;
    const double c = std::cos(a), s = std::sin(a);
    lm.mean = Eigen::Vector2d(p.pose.x_m + r * c, p.pose.y_m + r * s);
    Eigen::Matrix2d G;
    G << c, -r * s, s, r * c;
    lm.cov = G * R * G.transpose();
    lm.seen = true;
    initialised_[pi] = 1;
    return false;
  }
  const double dx = lm.mean.x() - p.pose.x_m, dy = lm.mean.y() - p.pose.y_m;
  const double q2 = dx * dx + dy * dy;
  if (q2 < 1e-18) return false;  // landmark estimate on the robot: no usable linearisation
  const double rho = std::sqrt(q2);
  const Eigen::Vector2d nu(
      o.range_m - (rho + n.range_mean_m),
      wrapAngle(o.bearing_rad - (std::atan2(dy, dx) - p.pose.yaw_rad + n.bearing_mean_rad)));
  Eigen::Matrix2d H;
  H << dx / rho, dy / rho, -dy / q2, dx / q2;
  const Eigen::Matrix2d S = H * lm.cov * H.transpose() + R;
  const Eigen::Matrix2d S_inv = S.inverse();
  const Eigen::Matrix<double, 2, 2> K = lm.cov * H.transpose() * S_inv;
  lm.mean += K * nu;
  lm.cov -= K * S * K.transpose();
  lm.cov = 0.5 * (lm.cov + lm.cov.transpose());
  const double det = S.determinant();
  log_lik_[pi] = -0.5 * nu.dot(S_inv * nu) - std::log(2.0 * kPi * std::sqrt(det));
  return true;
}

/// Particle-weighted mean error and mean squared error of one observation (ch. 3.2).
void FastSlamFilter::recordErrors(const Observation& o) {
  double mr = 0.0, mr2 = 0.0, mb = 0.0, mb2 = 0.0;
  for (std::size_t pi = 0; pi < n_particles_; ++pi) {
    double er = 0.0, eb = 0.0;
    predictedError(particles_[pi].pose,
                   particles_[pi].map[static_cast<std::size_t>(o.landmark)].mean, o, er, eb);
    mr += weight_[pi] * er;
    mr2 += weight_[pi] * er * er;
    mb += weight_[pi] * eb;
    mb2 += weight_[pi] * eb * eb;
  }
  SensorErrorSamples& e = result_.errors[static_cast<std::size_t>(o.sensor)];
  e.range_m.push_back(mr);
  e.range_sq_m2.push_back(mr2);
  e.bearing_rad.push_back(mb);
  e.bearing_sq_rad2.push_back(mb2);
}

/// State estimate of the stop: weighted mean pose (Sharma 2020 ch. 3.1).
void FastSlamFilter::recordMeanPose() {
  Pose2 mean;
  double sc = 0.0, ss = 0.0;
  for (std::size_t pi = 0; pi < n_particles_; ++pi) {
    mean.x_m += weight_[pi] * particles_[pi].pose.x_m;
    mean.y_m += weight_[pi] * particles_[pi].pose.y_m;
    sc += weight_[pi] * std::cos(particles_[pi].pose.yaw_rad);
    ss += weight_[pi] * std::sin(particles_[pi].pose.yaw_rad);
  }
  mean.yaw_rad = std::atan2(ss, sc);
  result_.mean_trajectory.push_back(mean);
}

/// Systematic resampling when the effective sample size is low (the uniform is drawn every stop).
void FastSlamFilter::resample() {
  const double u0 = uniform_(rng_);
  double sum_sq = 0.0;
  for (double w : weight_) sum_sq += w * w;
  const double ess = 1.0 / sum_sq;
  if (!(ess < config_.resample_fraction * static_cast<double>(n_particles_) ||
        (config_.resample_fraction >= 1.0 && n_particles_ > 1)))
    return;
  scratch_.clear();
  scratch_.reserve(n_particles_);
  double cumulative = weight_[0];
  std::size_t src = 0;
  for (std::size_t pi = 0; pi < n_particles_; ++pi) {
    const double target = (static_cast<double>(pi) + u0) / static_cast<double>(n_particles_);
    while (target > cumulative && src + 1 < n_particles_) cumulative += weight_[++src];
    scratch_.push_back(particles_[src]);  // deliberate copy: a particle owns its map
  }
  particles_.swap(scratch_);
  std::fill(weight_.begin(), weight_.end(), 1.0 / static_cast<double>(n_particles_));
  ++result_.resamplings;
}

}  // namespace

FastSlamResult runFastSlam(const NoiseProblem& problem, const NoiseSetting& assumed,
                           const FastSlamConfig& config, std::uint64_t seed, std::uint64_t stream) {
  config.validate();
  validateAssumed(problem, assumed);
  return FastSlamFilter(problem, assumed, config, seed, stream).run();
}

}  // namespace lidarcal::noise
