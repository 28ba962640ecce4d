// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// REF.json: measurements a user made by hand about a sequence (docs/FORMAT.md, "Reference
// measurements"): distances from the sensor to landmarks or walls at given stops, wall-to-wall
// spans, surveyed landmark centres, measured stop poses.

#include <cstddef>
#include <filesystem>

#include "common/reference.hpp"

namespace lidarcal::io {

/// Reads REF.json. Throws InputError naming the file and the entry (e.g. `distances[2].distance_m`)
/// for a malformed file, an unknown key or a value out of range.
Reference readReference(const std::filesystem::path& file);

/// Checks a reference against a sequence of `stops` stops: every stop index in range, each stop
/// measured at most once. Throws InputError naming the entry.
void checkReference(const Reference& ref, std::size_t stops, const std::filesystem::path& file);

/// Writes REF.json atomically (the format readReference reads).
void writeReference(const std::filesystem::path& file, const Reference& ref);

}  // namespace lidarcal::io
