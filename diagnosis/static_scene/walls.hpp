// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The walls of a room seen from one pose: runs of neighbouring bins without a depth jump, the
// incidence of each bin from the slope of its run, and straight pieces of the runs found by
// detectors/walls.hpp (findWallsInRun) in the bins' mean readings. Internal to the diagnosis
// library.

#include <vector>

#include "diagnosis/static_scene/bins.hpp"

namespace lidarcal::diagnosis::static_scene {

/// A wall line in normal form, the wall model's parameters for it.
struct Line {
  double theta = 0.0;  ///< direction of the normal from the sensor, radians
  double p = 0.0;      ///< distance from the sensor, metres: x cos(theta) + y sin(theta) = p
};

/// Finds the walls among the bins from their full-data locations `f`: sets each bin's wall, edge
/// (a depth discontinuity beside it, with the depths on both sides) and incidence (from the wall
/// line, else from the local slope of its run). Returns the wall lines, indexed by Bin::wall.
std::vector<Line> findWallLines(BinnedReadings& d, const std::vector<BinFit>& f);

}  // namespace lidarcal::diagnosis::static_scene
