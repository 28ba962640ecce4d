// SPDX-License-Identifier: BSD-3-Clause
#include "simulation/tape_reference.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "common/rng.hpp"

namespace lidarcal {

Reference tapeReference(const Truth& truth, const TapeConfig& config) {
  std::mt19937_64 rng = makeRng(config.seed, 0x7a9e);
  std::normal_distribution<double> normal(0.0, 1.0);
  Reference ref;
  const auto& poles = truth.scene.landmarks;
  for (std::size_t k = 0; k < truth.stops.size(); ++k) {
    const Pose2& at = truth.stops[k].actual;
    for (const Cylinder& l : poles) {
      const double dl = std::hypot(l.x_m - at.x_m, l.y_m - at.y_m);
      const double bl = std::atan2(l.y_m - at.y_m, l.x_m - at.x_m);
      bool hidden = dl > config.max_distance_m;
      for (const Cylinder& o : poles) {
        const double d = std::hypot(o.x_m - at.x_m, o.y_m - at.y_m);
        const double b = std::atan2(o.y_m - at.y_m, o.x_m - at.x_m);
        hidden = hidden || (d < dl && std::abs(std::remainder(b - bl, 2.0 * M_PI)) <
                                          std::asin(o.radius_m / d) + std::asin(l.radius_m / dl) +
                                              config.margin_rad);
      }
      if (hidden) continue;
      ReferenceDistance e;
      e.stop = k;
      e.target = ReferenceTarget::landmark;
      e.distance_m = dl + config.sigma_m * normal(rng);
      e.bearing_rad = std::remainder(bl - at.yaw_rad, 2.0 * M_PI);
      e.sigma_m = std::max(config.sigma_m, 1e-4);
      ref.distances.push_back(e);
    }
  }
  return ref;
}

}  // namespace lidarcal
