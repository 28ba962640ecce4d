// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Parametric bootstrap replicas of a sequence: the measured geometry simulated at landmark level
// (simulation/landmark_level.hpp) from a fit, with the stop poses redrawn as the model says they
// scatter. Internal to the diagnosis library.

#include <cstdint>
#include <set>
#include <utility>
#include <vector>

#include "diagnosis/sequence/refits.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::diagnosis::sequence {

/// Landmark-level simulation of the measured geometry from a fit (ids mapped to the fit's).
struct ReplicaPlan {
  simulation::LandmarkLevelConfig config;  ///< the simulator's scene, path, model and effects
  std::vector<int> ids;                    ///< simulated landmark l + 1 -> data id
  std::set<std::pair<std::size_t, int>> present;  ///< (scan, data landmark id) pairs of the data
};

/// The replicas of `fit`: its poses, centres, radius, range model and effect terms, the data's
/// beam grid and (scan, landmark) pairs; `radius_known`: the radius is published, not estimated.
ReplicaPlan replicaPlan(const LandmarkObservations& obs, const JointResult& fit, bool radius_known);

/// How a replica's stop poses are drawn: around the commanded path (scaled by 1 + scale), with
/// the model's position and heading scatter (Alhashimi et al. 2021 eq. 8).
struct PoseNoise {
  double sigma_s_m = 0.0;  ///< stop and go: a stop's position scatter, metres
  /// stop and go: its heading scatter, radians (0: headings as commanded)
  double sigma_psi_rad = 0.0;
  double scale = 0.0;  ///< odometry scale s: the true steps are 1 + s times the commanded ones
  /// The motion prior (continuous recording): each pose is the one before moved by the
  /// commanded step, with noise of std. dev. step_fraction s + step_floor_m per coordinate and
  /// heading_per_m s + heading_floor_rad in heading (s the commanded step length).
  bool motion = false;
  double step_fraction = 0.0;      ///< translation noise per metre of step
  double step_floor_m = 0.0;       ///< translation noise floor, metres
  double heading_per_m = 0.0;      ///< heading noise per metre of step, radians per metre
  double heading_floor_rad = 0.0;  ///< heading noise floor, radians
};

/// How the replicas of `fit`, a fit of model `cfg`, draw their poses.
PoseNoise poseNoise(const JointResult& fit, const JointConfig& cfg);

/// One replica: `plan` with its poses drawn by `noise` (stop and go: about the commanded ones;
/// under the motion prior: along the recorded steps, the odometry reported with its noise),
/// simulated with `seed`, keeping the data's (scan, landmark) pairs. `truth`, when given,
/// receives the true ranges of the kept sightings' beams.
LandmarkObservations simulateReplica(ReplicaPlan plan, const LandmarkObservations& obs,
                                     const PoseNoise& noise, std::uint64_t seed,
                                     std::vector<std::vector<double>>* truth = nullptr);

}  // namespace lidarcal::diagnosis::sequence
