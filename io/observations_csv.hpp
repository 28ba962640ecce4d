// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// observations.csv and odometry.csv: the input of noise estimation (docs/FORMAT.md).

#include <filesystem>
#include <vector>

#include "common/observation.hpp"

namespace lidarcal::io {

/// Header of observations.csv.
inline constexpr const char* kObservationsHeader = "stop,sensor,landmark,range_m,bearing_rad";
/// Header of odometry.csv.
inline constexpr const char* kOdometryHeader = "stop,dx_m,dy_m,dtheta_rad";

/// Reads observations.csv. Sensor and landmark ids are labels, any integers (landmark -1: the
/// association is unknown). Each row's `sensor` becomes the index of its label among the file's
/// sensor labels sorted ascending (0..S-1), each `landmark` likewise (0..L-1; -1 stays -1);
/// `sensor_labels` and `landmark_labels` (when given) receive the labels, so that outputs can
/// name them as the file did. Ids already numbered 0..N-1 keep their numbers. Throws InputError
/// (file, line, column, remedy) on a bad header, a malformed or non-finite field, a negative
/// stop or an id outside the int range.
std::vector<Observation> readObservations(const std::filesystem::path& file,
                                          std::vector<int>* sensor_labels = nullptr,
                                          std::vector<int>* landmark_labels = nullptr);
/// Writes observations.csv atomically (rows in the order given).
void writeObservations(const std::filesystem::path& file, const std::vector<Observation>& rows);

/// Reads odometry.csv. Rows must be stops 0, 1, 2, ... in order; stop 0 (the start) must have
/// zero motion. Throws InputError otherwise.
std::vector<OdometryStep> readOdometry(const std::filesystem::path& file);
/// Writes odometry.csv atomically.
void writeOdometry(const std::filesystem::path& file, const std::vector<OdometryStep>& rows);

}  // namespace lidarcal::io
