// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The simulator's companion file DIR/true_ranges.csv: the true range of every beam of every
// scan (docs/FORMAT.md). Written row by row so long simulations stream.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace lidarcal::io {

/// What a beam hit.
enum class TargetKind : std::uint8_t { none = 0, landmark = 1, clutter = 2, wall = 3 };
const char* toString(TargetKind kind);

/// Truth of one beam.
struct TrueRange {
  std::uint32_t scan = 0;  ///< scan index in the sequence (file order)
  std::uint32_t beam = 0;  ///< beam (point) index in the scan
  double range_m = 0.0;    ///< true distance to the surface hit; NaN when nothing was hit
  TargetKind target = TargetKind::none;  ///< kind of surface hit
  int target_id = 0;  ///< 1-based id within its kind (landmark ids match truth.json); 0 for none
  double incidence_rad = 0.0;  ///< angle between the beam and the surface normal
};

/// Streams rows to a CSV file (the caller makes the enclosing output atomic).
class TrueRangesWriter {
 public:
  explicit TrueRangesWriter(const std::filesystem::path& file);
  void write(const TrueRange& row);
  void close();  ///< flushes; throws InputError when the write failed

 private:
  std::filesystem::path file_;
  std::ofstream out_;
};

/// Reads a whole true_ranges.csv. Throws InputError on malformed rows.
std::vector<TrueRange> readTrueRanges(const std::filesystem::path& file);

}  // namespace lidarcal::io
