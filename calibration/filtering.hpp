#pragma once
// Filtering stage (seed 000 section 3.2 phase 3): every point of a scan moved along its beam
// to the corrected distance. Same points, same order; NaN stays NaN; labels and intensity kept.

#include "calibration/inversion.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::calibration {

struct FilteringStats {
  std::size_t points = 0;       ///< points in the scan
  std::size_t corrected = 0;    ///< returns moved to their corrected distance
  std::size_t unresolved = 0;   ///< returns without a root in the window (left as NaN)
};

/// Returns the corrected scan. The input is not modified.
io::Scan correctScan(const io::Scan& scan, const RangeInverter& inverter, FilteringStats* stats = nullptr);

}  // namespace lidarcal::calibration
