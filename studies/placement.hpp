// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Random landmark layouts for the Monte Carlo study (Alhashimi et al. 2021 section 4.1 draws a
// scene per simulation; section 4.3 keeps every landmark between 0.2 m and 5 m of every stop,
// visible and distinguishable). Landmarks are drawn one after the other, each accepted only when it
// is compatible with the ones before, so the first L landmarks of a layout of L' > L are a layout
// of L: studies over L add landmarks to the same scene, as the paper's field data drop them.

#include <cstdint>
#include <random>
#include <vector>

#include "common/scene.hpp"

namespace lidarcal::studies {

struct PlacementConfig {
  double radius_m = 0.12;      ///< landmark radius (the paper's field poles), metres
  double min_surface_m = 0.3;  ///< nearest surface distance from any stop, metres
  /// farthest surface distance from any stop, metres (noise 23 cm there)
  double max_surface_m = 4.0;
  /// distance of the centre from the path line, metres (no landmark on the path)
  double min_lateral_m = 0.5;
  double margin_m = 1.0;       ///< region extends this far beyond both path ends, metres
  double max_lateral_m = 3.5;  ///< region half-width across the path, metres
  /// angle the path subtends at the landmark (20 degrees): triangulable
  double min_spread_rad = 0.35;
  double min_separation_m = 0.5;  ///< centre-to-centre distance beyond two radii, metres
  /// free angle between two landmarks seen from any stop (2 degrees): no occlusion
  double min_gap_rad = 0.035;
  int max_attempts = 2000;  ///< candidate draws per landmark before the layout is started again
  int max_restarts = 100;   ///< layouts started again before giving up
  void validate() const;    ///< throws std::invalid_argument
};

/// Draws `count` landmarks around the commanded stops of `path` (only its commanded poses are
/// used). When the landmarks placed so far leave no room for the next one, the layout is drawn
/// again from the same stream (so a layout that needed this is not an extension of the smaller
/// ones). Throws std::runtime_error when max_restarts layouts fail.
std::vector<Cylinder> placeLandmarks(const PathSpec& path, int count, const PlacementConfig& config,
                                     std::mt19937_64& rng);

}  // namespace lidarcal::studies
