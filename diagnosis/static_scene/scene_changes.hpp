// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Whether a recording from one pose stayed one pose: beams that saw the scene change (an object
// carried in or out, a person walking past) and a sensor that moved. Internal to the diagnosis
// library.

#include <cstddef>

#include "diagnosis/static_scene/bins.hpp"

namespace lidarcal::diagnosis::static_scene {

/// Drops the bins that saw the scene change (sceneChanged) when they are at most half the bins
/// (beyond that the sensor, not the scene, moved; movedFraction has already looked at the
/// medians); returns how many were dropped. On a working site a third of the beams can see
/// objects carried in or out (docs/FINDINGS.md).
std::size_t dropChangedBins(BinnedReadings& d);

/// Whether the sensor moved during the recording: the beams' medians in the first and second half
/// of the scans differ beyond their noise, by different amounts (a drift moves them all alike).
double movedFraction(const BinnedReadings& d);

}  // namespace lidarcal::diagnosis::static_scene
