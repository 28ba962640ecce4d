// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/rig_start.hpp"

#include <cmath>
#include <set>

#include <ceres/ceres.h>

namespace lidarcal::calibration::rig {
namespace {

/// A sighting's centre (sensor frame) carried to the world by the vehicle's pose and a mounting,
/// against where the placed sensors put the pole.
struct CentreCost {
  double vx, vy, vyaw, qx, qy, px, py;
  template <typename T>
  bool operator()(const T* m, T* r) const {
    using std::cos;
    using std::sin;
    const T c = cos(m[2]), s = sin(m[2]);
    const T sx = m[0] + c * T(qx) - s * T(qy), sy = m[1] + s * T(qx) + c * T(qy);  // vehicle frame
    const double cv = std::cos(vyaw), sv = std::sin(vyaw);
    r[0] = T(vx) + T(cv) * sx - T(sv) * sy - T(px);
    r[1] = T(vy) + T(sv) * sx + T(cv) * sy - T(py);
    return true;
  }
};

Eigen::Vector2d toWorld(const Pose2& vehicle, const Pose2& mounting, const Eigen::Vector2d& q) {
  const Pose2 p = compose(vehicle, mounting);
  double x = 0.0, y = 0.0;
  p.toWorld(q.x(), q.y(), x, y);
  return {x, y};
}

/// The centres of the poles the placed sensors see: the mean of their sightings' centres.
std::map<int, Eigen::Vector2d> placedPoles(const RigObservations& obs,
                                           const std::vector<double>& flips, double radius,
                                           const std::vector<Pose2>& mountings,
                                           const std::vector<bool>& placed) {
  std::map<int, std::pair<Eigen::Vector2d, double>> sum;
  for (const RigSighting& s : obs.sightings) {
    if (!placed[s.sensor] || s.beams.empty()) continue;
    auto& [p, n] = sum.try_emplace(s.pole, Eigen::Vector2d::Zero(), 0.0).first->second;
    p += toWorld(obs.vehicle[s.stop], mountings[s.sensor],
                 sightingCentre(s, flips[s.sensor], radius));
    n += 1.0;
  }
  std::map<int, Eigen::Vector2d> out;
  for (const auto& [id, v] : sum) out[id] = v.first / v.second;
  return out;
}

/// Aligns sensor `s`'s mounting to the placed poles; false when it shares none with them.
bool align(const RigObservations& obs, std::size_t s, double flip, double radius,
           const std::map<int, Eigen::Vector2d>& poles, Pose2& mounting) {
  double m[3] = {mounting.x_m, mounting.y_m, mounting.yaw_rad};
  ceres::Problem problem;
  std::set<int> shared;
  for (const RigSighting& g : obs.sightings) {
    const auto it = poles.find(g.pole);
    if (g.sensor != s || g.beams.empty() || it == poles.end()) continue;
    shared.insert(g.pole);
    const Eigen::Vector2d q = sightingCentre(g, flip, radius);
    const Pose2& v = obs.vehicle[g.stop];
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<CentreCost, 2, 3>(
            new CentreCost{v.x_m, v.y_m, v.yaw_rad, q.x(), q.y(), it->second.x(), it->second.y()}),
        new ceres::HuberLoss(0.1), m);
  }
  if (shared.empty()) return false;
  // One shared pole fixes a translation only: the designed heading stays.
  if (shared.size() < 2) problem.SetManifold(m, new ceres::SubsetManifold(3, {2}));
  ceres::Solver::Options options;
  options.max_num_iterations = 50;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable()) return false;
  mounting = Pose2{m[0], m[1], m[2]};
  return true;
}

}  // namespace

Eigen::Vector2d sightingCentre(const RigSighting& s, double flip, double radius_m) {
  const BeamReading& mid = s.beams[s.beams.size() / 2];
  const double a = flip * mid.angle_rad;
  return {(mid.range_m + radius_m) * std::cos(a), (mid.range_m + radius_m) * std::sin(a)};
}

void startingGeometry(const RigObservations& obs, const std::vector<double>& flips, double radius_m,
                      std::size_t reference, std::vector<Pose2>& mountings,
                      std::map<int, Eigen::Vector2d>& poles) {
  std::vector<bool> placed(obs.sensors.size(), false);
  placed[reference] = true;
  for (bool progress = true; progress;) {
    progress = false;
    const std::map<int, Eigen::Vector2d> known =
        placedPoles(obs, flips, radius_m, mountings, placed);
    for (std::size_t s = 0; s < obs.sensors.size(); ++s)
      if (!placed[s] && align(obs, s, flips[s], radius_m, known, mountings[s]))
        placed[s] = progress = true;
  }
  for (std::size_t s = 0; s < placed.size(); ++s) placed[s] = true;
  poles = placedPoles(obs, flips, radius_m, mountings, placed);
}

}  // namespace lidarcal::calibration::rig
