// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Radius of thin, far poles from all the scans of one stop (docs/results/detection.md). A cheap
// lidar sees a 55 mm pole at 3-4.5 m with 3-9 beams: one arc cannot determine a radius
// (scan_detector.hpp refuses it: "radius not determined by the arc", or too few points for a free
// fit), but the scans of one stop see the same arc from the same pose, so their points pooled fit
// one circle (Alhashimi et al. 2021 section 3.1: the radius "not difficult to obtain" from the
// arcs; the free fit of circle_fit.hpp on the pooled points). The result is a radius hint in the
// stop's sensor frame; detectSequence's first pass fits those clusters with it fixed, and the joint
// radius over every stop (landmark_radius.hpp) follows as for larger poles.

#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "detectors/scan_detector.hpp"

namespace lidarcal::detectors {

/// Pooled circles of one stop: each a RadiusHint (sensor frame of the stop) for the clusters
/// that no scan alone could fit with a free radius. `scans` are the clouds of one stop (one
/// pose); `config` gives the segmentation, the inlier threshold t(range), the radius limits and
/// max_radius_uncertainty (the pooled radius must be determined to that fraction, noise taken
/// as max(fit RMS, t / 3)). A group of clusters (means within t + 2 cm of each other, one per
/// scan) is pooled when it was seen in at least half the stop's scans and at least 2 of them,
/// each cluster with at least 3 returns and no wider than a pole of radius_max_m. Stops of one
/// scan give nothing (no pooling; continuous motion).
std::vector<RadiusHint> pooledStopRadii(
    const std::vector<const pcl::PointCloud<pcl::PointXYZI>*>& scans,
    const DetectionConfig& config);

}  // namespace lidarcal::detectors
