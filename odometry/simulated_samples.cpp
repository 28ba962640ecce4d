// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/simulated_samples.hpp"

#include <random>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "common/rng.hpp"

namespace lidarcal::odometry {
namespace {

enum class Kind { straight, rotation, pivot, arc };

std::vector<Kind> enabledKinds(const MotionMix& mix) {
  std::vector<Kind> kinds;
  if (mix.straight) kinds.push_back(Kind::straight);
  if (mix.rotation) kinds.push_back(Kind::rotation);
  if (mix.pivot) kinds.push_back(Kind::pivot);
  if (mix.arc) kinds.push_back(Kind::arc);
  if (kinds.empty()) throw std::invalid_argument("simulateSamples: the motion mix is empty");
  return kinds;
}

/// Wheel speeds (left, right) of one motion of `kind`, the faster wheel at `speed`.
std::pair<double, double> wheelSpeeds(Kind kind, double speed, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double sign = unit(rng) < 0.5 ? -1.0 : 1.0;
  const bool left_first = unit(rng) < 0.5;
  switch (kind) {
    case Kind::straight:
      return {sign * speed, sign * speed};
    case Kind::rotation:
      return {-sign * speed, sign * speed};
    case Kind::pivot:
      return left_first ? std::pair{sign * speed, 0.0} : std::pair{0.0, sign * speed};
    case Kind::arc: {
      const double slower = sign * speed * (0.2 + 0.6 * unit(rng));
      return left_first ? std::pair{sign * speed, slower} : std::pair{slower, sign * speed};
    }
  }
  return {0.0, 0.0};
}

}  // namespace

std::vector<OdometrySample> simulateSamples(const SimulationSettings& settings) {
  const std::vector<Kind> kinds = enabledKinds(settings.mix);
  std::mt19937_64 rng = makeRng(settings.seed, 0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<OdometrySample> samples;
  samples.reserve(settings.samples);
  for (std::size_t k = 0; k < settings.samples; ++k) {
    OdometrySample s;
    const Kind kind = kinds[static_cast<std::size_t>(unit(rng) * kinds.size()) % kinds.size()];
    const double speed = settings.wheel_speed_rad_s * (0.5 + 0.5 * unit(rng));
    std::tie(s.left_wheel_rad_s, s.right_wheel_rad_s) = wheelSpeeds(kind, speed, rng);
    s.duration_s = settings.duration_s * (0.95 + 0.1 * unit(rng));
    const Eigen::Vector3d motion = predictedScanMatch(settings.truth, s);
    s.scan_match_x_m = motion[0] + settings.sigma_x_m * normal(rng);
    s.scan_match_y_m = motion[1] + settings.sigma_y_m * normal(rng);
    s.scan_match_theta_rad = motion[2] + settings.sigma_theta_rad * normal(rng);
    if (unit(rng) < settings.outlier_fraction) {
      s.scan_match_x_m += 0.2 * (unit(rng) - 0.5);
      s.scan_match_y_m += 0.2 * (unit(rng) - 0.5);
      s.scan_match_theta_rad += 0.4 * (unit(rng) - 0.5);
    }
    samples.push_back(s);
  }
  return samples;
}

}  // namespace lidarcal::odometry
