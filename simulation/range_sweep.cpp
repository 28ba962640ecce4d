// SPDX-License-Identifier: BSD-3-Clause
#include "simulation/range_sweep.hpp"

#include <random>
#include <stdexcept>

#include "common/pose2.hpp"
#include "common/rng.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::simulation {

void RangeSweepConfig::validate() const {
  if (distances_m.empty()) throw std::invalid_argument("RangeSweepConfig: no distance");
  for (double d : distances_m)
    if (!(d > radius_m))
      throw std::invalid_argument("RangeSweepConfig: every distance must exceed the pole's radius");
  if (!(radius_m > 0.0)) throw std::invalid_argument("RangeSweepConfig: radius_m must be positive");
  if (scans_per_stop == 0)
    throw std::invalid_argument("RangeSweepConfig: scans_per_stop must be at least 1");
  if (!(angle_increment_rad > 0.0))
    throw std::invalid_argument("RangeSweepConfig: angle_increment_rad must be positive");
  if (!(tape_error_m >= 0.0) || !(stated_sigma_m >= 0.0))
    throw std::invalid_argument(
        "RangeSweepConfig: tape_error_m and stated_sigma_m must not be negative");
  if (effects.ripple_amplitude_m != 0.0 && !(effects.ripple_wavelength_m > 0.0))
    throw std::invalid_argument("RangeSweepConfig: a ripple needs a positive wavelength");
}

RangeSweep simulateRangeSweep(const RangeSweepConfig& config, std::uint64_t seed) {
  config.validate();
  // The pole stands at the origin; the sensor faces it from -d along x at each stop.
  LandmarkLevelConfig c;
  c.landmarks = {Cylinder{0.0, 0.0, config.radius_m}};
  c.model = config.model;
  c.effects = config.effects;
  c.beams = true;
  c.angle_increment_rad = config.angle_increment_rad;
  c.angle_min_rad = -kPi;
  std::size_t first_scan = 0;
  for (double d : config.distances_m) {
    TruthStop s;
    s.commanded = s.actual = Pose2{-d, 0.0, 0.0};
    s.first_scan = first_scan;
    s.scans = config.scans_per_stop;
    first_scan += s.scans;
    c.stops.push_back(s);
  }
  RangeSweep out;
  out.obs = simulateLandmarkLevel(c, seed).obs;
  out.true_distance_m = config.distances_m;
  std::mt19937_64 tape_rng = makeRng(deriveSeed(seed, 0x7a9e5), 0);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t k = 0; k < config.distances_m.size(); ++k) {
    ReferenceDistance e;
    e.stop = k;
    e.distance_m = config.distances_m[k] + config.tape_error_m * normal(tape_rng);
    e.bearing_rad = 0.0;
    e.sigma_m = config.stated_sigma_m;
    out.reference.distances.push_back(e);
  }
  return out;
}

}  // namespace lidarcal::simulation
