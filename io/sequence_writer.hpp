// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The streaming sink of every importer: writes scan_NNNNNN.pcd files one at a time into a
// staged output directory and, at commit(), sequence.json (sensor name, range limits, beams)
// and, when the scans carry the wheels' angles, wheel_angles.csv.
// Nothing appears at the output path until commit(); a failed import leaves nothing behind.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "io/atomic_file.hpp"
#include "io/import.hpp"
#include "io/pcd_scan.hpp"
#include "io/wheel_angles_csv.hpp"

namespace lidarcal::io {

struct SequenceWriterConfig {
  /// write every N-th scan offered (scans 0, N, 2N, ...); >= 1; default 1 = all
  std::size_t every = 1;
  std::size_t max_scans = 0;  ///< stop after writing this many scans; 0 (default) = no limit
  bool overwrite = false;     ///< replace an existing output directory at commit(); default false
  /// encoding of the written PCD files; default binary
  PcdEncoding encoding = PcdEncoding::binary;

  /// Throws InputError when a value is out of range.
  void validate() const;
};

/// What was written.
struct SequenceWriteSummary {
  std::filesystem::path out;  ///< the sequence directory (final location)
  std::size_t offered = 0;    ///< scans offered by the importer
  std::size_t written = 0;    ///< scans written
  std::size_t min_beams = 0;  ///< fewest points in a written scan
  std::size_t max_beams = 0;  ///< most points in a written scan
  std::size_t points = 0;     ///< points written (one per beam)
  std::size_t returns = 0;    ///< points with coordinates (not NaN)
  std::size_t no_return = 0;  ///< readings that were NaN, inf or <= 0 (no return in the source)
  /// finite positive readings outside [range_min, range_max], written as NaN
  std::size_t outside_limits = 0;
  std::size_t with_intensity = 0;  ///< written scans that carry an `intensity` field
  /// lower range limit recorded in sequence.json, metres (smallest over the scans)
  double range_min_m = 0.0;
  /// upper range limit recorded (largest over the scans; inf when unbounded: then not recorded)
  double range_max_m = 0.0;
  /// written scans with the wheels' angles (rows of wheel_angles.csv; 0: no file written)
  std::size_t with_wheels = 0;
};

class SequenceWriter {
 public:
  /// Prepares a staging directory beside `out`. Throws InputError when `out` exists (without
  /// overwrite) or cannot be created.
  SequenceWriter(const std::filesystem::path& out, const SequenceWriterConfig& config);

  /// Offers the next scan of the recording: every N-th one is converted to points
  /// (x = r cos a, y = r sin a, z = 0; NaN for readings without return or outside the scan's
  /// range limits) and written. Returns false once max_scans scans have been written.
  bool add(const RawScan& scan);

  /// The next scan written begins a new stop even if its VIEWPOINT equals the previous one's
  /// (recorded in sequence.json `stop_starts`).
  void startStop() { start_next_ = true; }

  /// Writes sequence.json and moves the directory into place. Throws InputError when no scan was
  /// written.
  SequenceWriteSummary commit(const std::string& sensor_name);

  const SequenceWriteSummary& summary() const { return summary_; }

 private:
  SequenceWriterConfig config_;
  StagedDirectory dir_;
  SequenceWriteSummary summary_;
  Scan scratch_;                          // reused for every scan: memory stays that of one scan
  bool start_next_ = false;               // startStop() called since the last scan written
  std::vector<std::string> stop_starts_;  // names of the scans that begin a stop (startStop)
  std::vector<WheelAngleRow> wheels_;     // rows of wheel_angles.csv, one per scan with wheels
};

}  // namespace lidarcal::io
