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
// (seed 003 ch. 3.2), without the assumed bias.
void predictedError(const Pose2& pose, const Eigen::Vector2d& lm, const Observation& o, double& er, double& eb) {
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

FastSlamResult runFastSlam(const NoiseProblem& problem, const NoiseSetting& assumed, const FastSlamConfig& config,
                           std::uint64_t seed, std::uint64_t stream) {
  config.validate();
  if (static_cast<int>(assumed.sensors.size()) < problem.sensors)
    throw InputError("", "assumed noise", "has " + std::to_string(assumed.sensors.size()) + " sensors, the data " +
                                              std::to_string(problem.sensors));
  for (int s = 0; s < problem.sensors; ++s) {
    const SensorNoise& n = assumed.sensors[static_cast<std::size_t>(s)];
    if (!(n.range_var_m2 > 0.0) || !(n.bearing_var_rad2 > 0.0))
      throw InputError("", "assumed noise of sensor " + std::to_string(s), "variances must be positive");
  }

  // Without process noise every particle follows the same path with the same map and weight:
  // one particle gives the same result (up to rounding) at 1/N of the cost.
  const ProcessNoise& q = assumed.process;
  const bool deterministic = config.collapse_identical_particles && q.dx_var_m2 == 0.0 && q.dy_var_m2 == 0.0 &&
                             q.dtheta_var_rad2 == 0.0;
  const auto n_particles = deterministic ? std::size_t{1} : static_cast<std::size_t>(config.particles);
  const auto n_landmarks = static_cast<std::size_t>(problem.landmarks);
  std::vector<Particle> particles(n_particles, Particle{Pose2{}, std::vector<LandmarkEkf>(n_landmarks)});
  std::vector<Particle> scratch;
  std::vector<double> weight(n_particles, 1.0 / static_cast<double>(n_particles));
  std::vector<double> log_lik(n_particles);
  std::vector<char> initialised(n_particles);

  FastSlamResult result;
  result.errors.resize(static_cast<std::size_t>(problem.sensors));
  result.mean_trajectory.reserve(static_cast<std::size_t>(problem.stops));

  auto rng = makeRng(seed, stream);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double sq_dx = std::sqrt(q.dx_var_m2), sq_dy = std::sqrt(q.dy_var_m2), sq_dt = std::sqrt(q.dtheta_var_rad2);

  for (int k = 0; k < problem.stops; ++k) {
    // Prediction (seed 003 ch. 3.1): commanded motion plus sampled process noise.
    if (k > 0) {
      const OdometryStep& u = problem.odometry[static_cast<std::size_t>(k)];
      for (auto& p : particles) {
        const double n1 = normal(rng), n2 = normal(rng), n3 = normal(rng);
        p.pose = compose(p.pose, u.dx_m + sq_dx * n1, u.dy_m + sq_dy * n2, u.dtheta_rad + sq_dt * n3);
      }
    }

    // Update: one EKF per particle and landmark, weights by the innovation likelihood.
    const std::size_t begin = problem.stop_begin[static_cast<std::size_t>(k)];
    const std::size_t end = problem.stop_begin[static_cast<std::size_t>(k) + 1];
    std::vector<char> used(end - begin, 1);
    for (std::size_t i = begin; i < end; ++i) {
      const Observation& o = problem.observations[i];
      const SensorNoise& n = assumed.sensors[static_cast<std::size_t>(o.sensor)];
      const Eigen::Matrix2d R = Eigen::Vector2d(n.range_var_m2, n.bearing_var_rad2).asDiagonal();
      bool any_update = false;
      for (std::size_t pi = 0; pi < n_particles; ++pi) {
        Particle& p = particles[pi];
        LandmarkEkf& lm = p.map[static_cast<std::size_t>(o.landmark)];
        initialised[pi] = 0;
        log_lik[pi] = 0.0;  // log-likelihood; 0 for particles not updated
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
          initialised[pi] = 1;
          continue;
        }
        const double dx = lm.mean.x() - p.pose.x_m, dy = lm.mean.y() - p.pose.y_m;
        const double q2 = dx * dx + dy * dy;
        if (q2 < 1e-18) continue;  // landmark estimate on the robot: no usable linearisation
        const double rho = std::sqrt(q2);
        const Eigen::Vector2d nu(o.range_m - (rho + n.range_mean_m),
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
        log_lik[pi] = -0.5 * nu.dot(S_inv * nu) - std::log(2.0 * kPi * std::sqrt(det));
        any_update = true;
      }
      if (any_update) {
        // Weights times likelihoods, in the log domain against underflow.
        const double top = *std::max_element(log_lik.begin(), log_lik.end());
        for (std::size_t pi = 0; pi < n_particles; ++pi) weight[pi] *= std::exp(log_lik[pi] - top);
        result.log_evidence += top + normalise(weight);
      }
      if (config.skip_initialising) {
        bool all_init = true;
        for (std::size_t pi = 0; pi < n_particles; ++pi) all_init = all_init && initialised[pi];
        if (all_init) used[i - begin] = 0;
      }
    }

    // Predicted errors of this stop's observations against the updated particles (ch. 3.2).
    for (std::size_t i = begin; i < end; ++i) {
      if (!used[i - begin]) continue;
      const Observation& o = problem.observations[i];
      double mr = 0.0, mr2 = 0.0, mb = 0.0, mb2 = 0.0;
      for (std::size_t pi = 0; pi < n_particles; ++pi) {
        double er = 0.0, eb = 0.0;
        predictedError(particles[pi].pose, particles[pi].map[static_cast<std::size_t>(o.landmark)].mean, o, er, eb);
        mr += weight[pi] * er;
        mr2 += weight[pi] * er * er;
        mb += weight[pi] * eb;
        mb2 += weight[pi] * eb * eb;
      }
      SensorErrorSamples& e = result.errors[static_cast<std::size_t>(o.sensor)];
      e.range_m.push_back(mr);
      e.range_sq_m2.push_back(mr2);
      e.bearing_rad.push_back(mb);
      e.bearing_sq_rad2.push_back(mb2);
    }

    // State estimate of the stop: weighted mean pose (seed 003 ch. 3.1).
    Pose2 mean;
    double sc = 0.0, ss = 0.0;
    for (std::size_t pi = 0; pi < n_particles; ++pi) {
      mean.x_m += weight[pi] * particles[pi].pose.x_m;
      mean.y_m += weight[pi] * particles[pi].pose.y_m;
      sc += weight[pi] * std::cos(particles[pi].pose.yaw_rad);
      ss += weight[pi] * std::sin(particles[pi].pose.yaw_rad);
    }
    mean.yaw_rad = std::atan2(ss, sc);
    result.mean_trajectory.push_back(mean);

    // Systematic resampling when the effective sample size is low.
    const double u0 = uniform(rng);
    double sum_sq = 0.0;
    for (double w : weight) sum_sq += w * w;
    const double ess = 1.0 / sum_sq;
    if (ess < config.resample_fraction * static_cast<double>(n_particles) ||
        (config.resample_fraction >= 1.0 && n_particles > 1)) {
      scratch.clear();
      scratch.reserve(n_particles);
      double cumulative = weight[0];
      std::size_t src = 0;
      for (std::size_t pi = 0; pi < n_particles; ++pi) {
        const double target = (static_cast<double>(pi) + u0) / static_cast<double>(n_particles);
        while (target > cumulative && src + 1 < n_particles) cumulative += weight[++src];
        scratch.push_back(particles[src]);  // deliberate copy: a particle owns its map
      }
      particles.swap(scratch);
      std::fill(weight.begin(), weight.end(), 1.0 / static_cast<double>(n_particles));
      ++result.resamplings;
    }
  }
  return result;
}

}  // namespace lidarcal::noise
