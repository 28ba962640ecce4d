// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Converts detection's landmarks.csv (one row per detected landmark in a scan) into
// observations.csv rows, and a sequence's commanded stop poses into odometry.csv rows, so real
// recordings feed noise estimation (docs/FORMAT.md).
//
// Note for the merger: this file carries its own small reader of the landmarks.csv columns it
// needs (stop, landmark, bearing_rad, range_m, radius_m, looked up by header name); the full
// reader/writer lives in io/landmarks_csv.* on the detection branch and can replace it.

#include <filesystem>
#include <vector>

#include "common/observation.hpp"
#include "io/sequence.hpp"

namespace lidarcal::io {

/// Which point of a round landmark the converted range refers to.
enum class RangeReference {
  /// range_m as detected: sensor to the fitted centre (default; the point a landmark map holds)
  centre,
  /// range_m - radius_m: sensor to the nearest point of the surface (what a single beam reads)
  surface,
};

/// Reads landmarks.csv (io/landmarks_csv.hpp) and returns one observation per row, sorted by
/// stop: sensor 0, the row's stop and landmark id, its range (per `reference`) and bearing.
/// Throws InputError (file, line, column) as readLandmarksCsv does.
std::vector<Observation> observationsFromLandmarksCsv(const std::filesystem::path& file,
                                                      RangeReference reference);

/// The commanded motion into every stop: the relative pose of stop k in the frame of stop k-1
/// (stop 0: zero motion).
std::vector<OdometryStep> odometryFromStops(const std::vector<Stop>& stops);

}  // namespace lidarcal::io
