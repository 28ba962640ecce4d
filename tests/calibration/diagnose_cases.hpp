#pragma once
// Simulated sequences with one effect hidden in them (or none), for the diagnosis tests and
// bench/diagnose_accuracy. The paper field of seed 000 section 4.3 at the landmark level: five
// poles of 0.12 m (radius published), ten stops of 0.30 m, ten scans per stop, seed 004's bias
// and squared noise (2 cm at 3 m), stop positions scattered by 2 cm, sighting bearings by 0.2
// degree, and the room's walls behind the poles (the background of mixed pixels). Which size
// (and sign) the effect takes is drawn from the case seed; the tests only look at the name.

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>

#include "common/rng.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::test {

struct HiddenEffectCase {
  simulation::LandmarkLevelConfig config;  ///< the scene with the effect
  std::uint64_t seed = 0;                  ///< simulator seed
  std::string size;                        ///< the drawn size in words (messages only)
};

inline simulation::LandmarkLevelConfig paperFieldLandmarkLevel() {
  simulation::LandmarkLevelConfig c;
  c.landmarks = {{1.5, 0.75, 0.12}, {0.3, 2.2, 0.12}, {2.4, 3.4, 0.12}, {3.9, -1.3, 0.12}, {0.9, -2.8, 0.12}};
  c.walls = {{-1.5, -3.8, 5.0, -3.8}, {5.0, -3.8, 5.0, 4.5}, {5.0, 4.5, -1.5, 4.5}, {-1.5, 4.5, -1.5, -3.8}};
  c.path.stops = 10;
  c.path.step_m = 0.30;
  c.path.scans_per_stop = 10;
  c.path.sigma_s_m = 0.02;
  c.path.sigma_psi_rad = 0.0;  // the seeds' model: no heading error shared by a stop
  c.model.bias.alpha = {0.0525, 0.8838, 0.0584};
  c.model.noise.kind = NoiseKind::squared;
  c.model.noise.sigma_e = 0.0019176;
  c.model.range_min_m = 0.2;
  c.model.range_max_m = 6.0;
  c.sigma_theta_rad = deg2rad(0.2);
  c.beams = true;
  return c;
}

/// The case `case_seed` of effect `effect` ("none" for clean data). Sizes: around the issue's
/// "realistic" examples, drawn uniformly in the ranges below.
inline HiddenEffectCase hiddenEffectCase(const std::string& effect, std::uint64_t case_seed) {
  HiddenEffectCase h;
  h.config = paperFieldLandmarkLevel();
  h.seed = deriveSeed(case_seed, 77);
  auto rng = makeRng(case_seed, 91);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double sign = u(rng) < 0.5 ? -1.0 : 1.0;
  auto& c = h.config;
  const double scans = static_cast<double>(c.path.stops * c.path.scans_per_stop);
  char buf[160];
  if (effect == "none") {
    h.size = "clean";
  } else if (effect == "incidence_noise") {
    c.effects.incidence_noise_exponent = 1.0 + 0.5 * u(rng);  // sigma (1 / cos phi)^gamma, gamma in [1, 1.5]
    std::snprintf(buf, sizeof buf, "gamma %.2f", c.effects.incidence_noise_exponent);
  } else if (effect == "incidence_bias") {
    c.effects.incidence_bias_m = sign * (0.02 + 0.02 * u(rng));  // 2-4 cm at grazing incidence
    std::snprintf(buf, sizeof buf, "b %.3f m", c.effects.incidence_bias_m);
  } else if (effect == "landmark_bias") {
    // Per-landmark offsets with sigma 2-2.5 cm: a random pattern scaled to that RMS about its
    // mean (the mean is a common offset, which the bias polynomial's alpha_0 takes).
    std::normal_distribution<double> n(0.0, 1.0);
    const double sigma = 0.02 + 0.005 * u(rng);
    double mean = 0.0, ss = 0.0;
    for (auto& l : c.landmarks) {
      l.range_offset_m = n(rng);
      mean += l.range_offset_m / static_cast<double>(c.landmarks.size());
    }
    for (const auto& l : c.landmarks) ss += (l.range_offset_m - mean) * (l.range_offset_m - mean);
    const double rms = std::sqrt(ss / static_cast<double>(c.landmarks.size()));
    const double common = 0.02 * (u(rng) - 0.5);  // and a common part, up to +-1 cm
    for (auto& l : c.landmarks) l.range_offset_m = common + (l.range_offset_m - mean) * sigma / rms;
    std::snprintf(buf, sizeof buf, "offsets %.3f %.3f %.3f %.3f %.3f m", c.landmarks[0].range_offset_m,
                  c.landmarks[1].range_offset_m, c.landmarks[2].range_offset_m, c.landmarks[3].range_offset_m,
                  c.landmarks[4].range_offset_m);
  } else if (effect == "heading_error") {
    c.path.sigma_psi_rad = deg2rad(1.0 + 0.5 * u(rng));  // per stop, 1-1.5 degrees
    std::snprintf(buf, sizeof buf, "sigma_psi %.2f deg", rad2deg(c.path.sigma_psi_rad));
  } else if (effect == "range_drift") {
    const double total = sign * (0.03 + 0.01 * u(rng));  // 3-4 cm over the sequence
    c.effects.range_drift_m_per_scan = total / (scans - 1.0);
    std::snprintf(buf, sizeof buf, "%.3f m over the sequence", total);
  } else if (effect == "mixed_pixels") {
    c.effects.mixed_pixel_fraction = 0.05 + 0.05 * u(rng);  // 5-10 % of the outermost beams
    std::snprintf(buf, sizeof buf, "fraction %.3f", c.effects.mixed_pixel_fraction);
  } else if (effect == "angle_offset") {
    c.mount_yaw_rad = sign * deg2rad(2.0 + u(rng));  // 2-3 degrees
    std::snprintf(buf, sizeof buf, "%.2f deg", rad2deg(c.mount_yaw_rad));
  } else if (effect == "range_noise_law") {
    // sigma = sigma_e f^k with k far from 2, the same noise at 3 m.
    const double k = u(rng) < 0.5 ? 0.5 + 0.5 * u(rng) : 3.0 + 0.5 * u(rng);
    const double at3 = c.model.noise.stddev(3.0, c.model.bias);
    c.model.noise.kind = NoiseKind::power;
    c.model.noise.exponent = k;
    c.model.noise.sigma_e = at3 / std::pow(c.model.bias(3.0), k);
    std::snprintf(buf, sizeof buf, "exponent %.2f", k);
  } else if (effect == "odometry_scale") {
    c.path.step_error_fraction = sign * (0.03 + 0.02 * u(rng));  // true steps 3-5 % off
    std::snprintf(buf, sizeof buf, "step error %.3f", c.path.step_error_fraction);
  } else {
    throw std::invalid_argument("hiddenEffectCase: unknown effect " + effect);
  }
  if (effect != "none") h.size = buf;
  return h;
}

}  // namespace lidarcal::test
