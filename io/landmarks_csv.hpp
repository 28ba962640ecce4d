// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// landmarks.csv, written by `lidarcal detect`: one row per landmark detection (docs/FORMAT.md).
// Streamed row by row (the caller makes the enclosing output directory atomic).

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace lidarcal::io {

/// One detection of a landmark in one scan. Positions in the sensor frame of that scan.
struct LandmarkRow {
  std::string file;          ///< scan file name (no directory)
  std::size_t stop = 0;      ///< stop index in the sequence (0-based)
  int landmark = 0;          ///< landmark id (>= 1), the `label` of its points
  double bearing_rad = 0.0;  ///< bearing of the centre, radians, (-pi, pi]
  double range_m = 0.0;      ///< distance from the sensor to the centre, metres
  double centre_x_m = 0.0;   ///< centre x, metres
  double centre_y_m = 0.0;   ///< centre y, metres
  double radius_m = 0.0;     ///< radius used for the centre, metres
  std::size_t n_points = 0;  ///< points on the circle (labelled with the id)
  double rms_m = 0.0;        ///< RMS distance of those points to the circle, metres
};

/// The header line (without newline).
const char* landmarksCsvHeader();

class LandmarksCsvWriter {
 public:
  explicit LandmarksCsvWriter(const std::filesystem::path& file);
  void write(const LandmarkRow& row);
  void close();  ///< flushes; throws InputError when the write failed

 private:
  std::filesystem::path file_;
  std::ofstream out_;
};

/// Reads a whole landmarks.csv. Throws InputError naming the line and column at fault.
std::vector<LandmarkRow> readLandmarksCsv(const std::filesystem::path& file);

}  // namespace lidarcal::io
