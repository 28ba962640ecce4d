// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The walls a sequence shows at chosen stops: every scan's lines (wall_tracks.hpp), grouped into
// the surfaces of each stop.

#include <cstddef>
#include <set>
#include <vector>

#include "common/landmark_observations.hpp"
#include "detectors/scan_detector.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/sequence.hpp"

namespace lidarcal::detectors {

/// Walls of every scan (from `load`) at the stops `stops` of `seq`, grouped into the surfaces of
/// each stop; the line fits take the detection's inlier threshold (threshold_m, threshold_per_m2).
std::vector<WallSighting> wallsAtStops(const io::Sequence& seq, const std::set<std::size_t>& stops,
                                       const ScanLoader& load, const DetectionConfig& detection);

}  // namespace lidarcal::detectors
