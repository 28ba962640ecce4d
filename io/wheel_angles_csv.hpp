// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// wheel_angles.csv: each wheel's cumulative angle at each scan, as a robot's encoders give it
// (docs/FORMAT.md). The input of `lidarcal odometry-drive` beside detect's landmarks.csv.

#include <filesystem>
#include <string>
#include <vector>

namespace lidarcal::io {

/// The wheels' angles when one scan was taken.
struct WheelAngleRow {
  std::string file;        ///< the scan's file name, as in landmarks.csv
  double left_rad = 0.0;   ///< the left wheel's cumulative angle, radians
  double right_rad = 0.0;  ///< the right wheel's cumulative angle, radians
};

/// The header line (without newline).
const char* wheelAnglesCsvHeader();

/// Reads a whole wheel_angles.csv: at least two rows, in time order, each file once. Throws
/// InputError naming the line and column at fault.
std::vector<WheelAngleRow> readWheelAnglesCsv(const std::filesystem::path& file);

/// Writes one atomically (for simulations and conversions).
void writeWheelAnglesCsv(const std::filesystem::path& file, const std::vector<WheelAngleRow>& rows);

}  // namespace lidarcal::io
