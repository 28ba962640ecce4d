// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Cross-validation of a sequence: each sighting's fold (by scan position within its stop), the
// split into the sightings fitted on and those scored, and the readings spread over their grid
// cells for the scoring (diagnosis/dequantise.hpp). Internal to the diagnosis library.

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "common/landmark_observations.hpp"

namespace lidarcal::diagnosis::sequence {

/// Fold of each sighting: scan position within its stop modulo K, or (stop + landmark) mod K
/// when some stop has a single scan (its pose must be learnt from its other sightings).
std::vector<int> foldOfEachSighting(const LandmarkObservations& obs, int k);

/// Fold f of `fold` (the fold of each sighting): the other folds' sightings to fit on and fold
/// f's to score; nothing when fold f holds no sighting.
std::optional<std::pair<LandmarkObservations, LandmarkObservations>> foldSplit(
    const LandmarkObservations& obs, const std::vector<int>& fold, int f);

/// The readings' grid (detectReadingGrid over every finite beam; 0: none).
double readingGrid(const LandmarkObservations& obs);

/// The sightings with every finite reading spread uniformly over its grid cell of width q
/// (dequantise, seeded by `seed`): where the readings lie on a grid, the continuous models are
/// scored on these, the rounded model on the readings as recorded.
LandmarkObservations dequantised(const LandmarkObservations& obs, double q, std::uint64_t seed);

}  // namespace lidarcal::diagnosis::sequence
