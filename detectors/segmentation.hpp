// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Splits a 2D scan into clusters of neighbouring returns, walking the beams in scan order: a new
// cluster starts where two consecutive returns are farther apart than a range-dependent gap (the
// smaller of a fixed gap growing with range and the adaptive breakpoint of Borges & Aldon) or
// where more than a few beams in a row have no return. A 360-degree scan is closed: the last
// cluster joins the first when the two ends are neighbours.

#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/types.h>

namespace lidarcal::detectors {

struct SegmentationConfig {
  /// Consecutive returns farther apart than gap_m + gap_per_m * range split a cluster, metres.
  /// Default 0.10.
  double gap_m = 0.10;
  /// Growth of the gap with range (beam spacing and noise both grow with it), metres per metre.
  /// Default 0.06.
  double gap_per_m = 0.06;
  /// Beams without return (NaN) tolerated inside a cluster. Default 1.
  int max_missing_beams = 1;
  /// Adaptive breakpoint (Borges & Aldon 2004): neighbours at range r, dphi apart, also split
  /// when farther apart than r sin(dphi) / sin(lambda - dphi) + the noise allowance below, i.e.
  /// when the surface between them would be inclined less than lambda to the beams. On a sensor
  /// with fine angular steps (0.25 degree) this cuts the mixed pixels that bridge a near target
  /// and the wall behind it, which the fixed gap above lets through. lambda in radians; 0 turns
  /// it off. Default 10 degrees.
  double breakpoint_angle_rad = 0.17453292519943295;
  double breakpoint_noise_m = 0.02;        ///< noise allowance at range 0, metres. Default 0.02
  double breakpoint_noise_per_m2 = 0.005;  ///< its growth with range squared, 1/m. Default 0.005

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// Clusters of a scan: point indices in beam order (a cluster closed across the end of the scan
/// continues from the last beams to the first ones). NaN points belong to no cluster.
std::vector<pcl::Indices> segmentScan(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                                      const SegmentationConfig& config);

/// Median angular step between consecutive beams that both have a return, radians (0 when the
/// scan has fewer than two neighbouring returns).
double estimateAngularStep(const pcl::PointCloud<pcl::PointXYZI>& cloud);

}  // namespace lidarcal::detectors
