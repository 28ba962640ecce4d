// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Odometry tuples (docs/FORMAT.md, "Odometry tuples"): a stream of JSON objects, one per
// interval, read one after another (not by lines: two objects may share a line, an object may
// span lines), each {"T": s, "phi_l": rad/s, "phi_r": rad/s, "sm": [x m, y m, theta rad]}.

#include <filesystem>
#include <vector>

#include "common/odometry_sample.hpp"

namespace lidarcal::io {

/// Reads every tuple of `file`, in order. Throws InputError naming the file, the object (its
/// number from 1 and the line it starts on) and the field: a missing field, a value that is not
/// a finite number, T <= 0, `sm` without 3 numbers, a truncated or malformed object, a file that
/// holds no object.
std::vector<OdometrySample> readOdometryTuples(const std::filesystem::path& file);

}  // namespace lidarcal::io
