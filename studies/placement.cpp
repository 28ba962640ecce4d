// SPDX-License-Identifier: BSD-3-Clause
#include "studies/placement.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "common/errors.hpp"

namespace lidarcal::studies {

void PlacementConfig::validate() const {
  if (!(radius_m > 0.0)) throw std::invalid_argument("PlacementConfig: radius_m must be positive");
  if (!(min_surface_m >= 0.0 && max_surface_m > min_surface_m))
    throw std::invalid_argument("PlacementConfig: need 0 <= min_surface_m < max_surface_m");
  if (!(min_lateral_m >= 0.0 && max_lateral_m > min_lateral_m))
    throw std::invalid_argument("PlacementConfig: need 0 <= min_lateral_m < max_lateral_m");
  if (!(margin_m >= 0.0) || !(min_spread_rad >= 0.0) || !(min_separation_m >= 0.0) ||
      !(min_gap_rad >= 0.0))
    throw std::invalid_argument("PlacementConfig: margins and angles must be non-negative");
  if (max_attempts < 1 || max_restarts < 0)
    throw std::invalid_argument("PlacementConfig: max_attempts must be >= 1 and max_restarts >= 0");
}

namespace {

/// Whether candidate c may join `placed`, seen from the commanded stops.
bool acceptable(const Cylinder& c, const std::vector<Cylinder>& placed,
                const std::vector<Pose2>& stops, const PlacementConfig& cfg) {
  double lo = 1e300, hi = -1e300;
  for (const Pose2& p : stops) {
    const double d = std::hypot(c.x_m - p.x_m, c.y_m - p.y_m) - c.radius_m;
    if (d < cfg.min_surface_m || d > cfg.max_surface_m) return false;
    const double a = std::atan2(c.y_m - p.y_m, c.x_m - p.x_m);
    lo = std::min(lo, a);
    hi = std::max(hi, a);
  }
  // Bearings from a straight path to a point off it span less than pi: no wrap-around here.
  if (hi - lo < cfg.min_spread_rad) return false;
  for (const Cylinder& o : placed) {
    if (std::hypot(c.x_m - o.x_m, c.y_m - o.y_m) < c.radius_m + o.radius_m + cfg.min_separation_m)
      return false;
    for (const Pose2& p : stops) {
      const double dc = std::hypot(c.x_m - p.x_m, c.y_m - p.y_m),
                   dold = std::hypot(o.x_m - p.x_m, o.y_m - p.y_m);
      const double gap = std::abs(wrapAngle(std::atan2(c.y_m - p.y_m, c.x_m - p.x_m) -
                                            std::atan2(o.y_m - p.y_m, o.x_m - p.x_m)));
      if (gap < std::asin(c.radius_m / dc) + std::asin(o.radius_m / dold) + cfg.min_gap_rad)
        return false;
    }
  }
  return true;
}

}  // namespace

std::vector<Cylinder> placeLandmarks(const PathSpec& path, int count, const PlacementConfig& config,
                                     std::mt19937_64& rng) {
  config.validate();
  std::vector<Pose2> stops;
  for (int k = 0; k < path.stops; ++k) stops.push_back(commandedPose(path, k));
  const double length = path.step_m * std::max(path.stops - 1, 0);
  const double c = std::cos(path.start.yaw_rad), s = std::sin(path.start.yaw_rad);
  std::uniform_real_distribution<double> along(-config.margin_m, length + config.margin_m);
  std::uniform_real_distribution<double> across(config.min_lateral_m, config.max_lateral_m);
  std::uniform_int_distribution<int> side(0, 1);
  for (int restart = 0; restart <= config.max_restarts; ++restart) {
    std::vector<Cylinder> out;
    for (int l = 0; l < count; ++l) {
      bool placed = false;
      for (int attempt = 0; attempt < config.max_attempts && !placed; ++attempt) {
        const double u = along(rng), v = across(rng) * (side(rng) ? 1.0 : -1.0);
        const Cylinder cand{path.start.x_m + u * c - v * s, path.start.y_m + u * s + v * c,
                            config.radius_m};
        if (acceptable(cand, out, stops, config)) {
          out.push_back(cand);
          placed = true;
        }
      }
      if (!placed) break;
    }
    if (static_cast<int>(out.size()) == count) return out;
  }
  // Reachable from the command line (a short path, many landmarks): the user can act on it.
  char what[160];
  std::snprintf(what, sizeof what,
                "no room for %d landmarks of radius %g m beside a path of %d stops %g m apart (%d "
                "layouts tried)",
                count, config.radius_m, path.stops, path.step_m, config.max_restarts + 1);
  throw DataError("", "landmark layout", what,
                  "lengthen the path (more stops or a longer step) or place fewer landmarks");
}

}  // namespace lidarcal::studies
