// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A recording's polar scan as the point cloud the detectors and the PCD files take: point i is
// beam i in the sensor frame, NaN where the beam has no return or reads outside the scan's range
// window. The importers' sequence writer and the field watcher (watch/) share this rule.

#include <cstddef>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "io/import.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::io {

/// What became of the beams of one scan.
struct CloudCounts {
  std::size_t returns = 0;         ///< beams with a reading inside the range window
  std::size_t no_return = 0;       ///< beams reading NaN, inf or <= 0
  std::size_t outside_limits = 0;  ///< beams reading outside [range_min_m, range_max_m]
};

/// Fills `cloud` (resized to the scan's beams) with the scan's points; intensities when the scan
/// has them, else 0. Throws std::invalid_argument when angles, ranges or intensities differ in
/// number.
CloudCounts toCloud(const RawScan& scan, pcl::PointCloud<pcl::PointXYZI>& cloud);

/// A sequence's scan as polar readings (the inverse of toCloud for the points with a return):
/// pose from VIEWPOINT, each point's bearing and distance, NaN where it has none; the reporting
/// window as given (the sequence's, when known).
RawScan toRawScan(const Scan& scan, double range_min_m, double range_max_m);

}  // namespace lidarcal::io
