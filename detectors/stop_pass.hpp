// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One pass of detection over a sequence, stop by stop: the scans of a stop detected (on threads,
// a window ahead), handed on as a block, and linked into tracks. Internal to detectors/: the
// sequence detector runs it for its passes and again to replay them.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "common/pose2.hpp"
#include "detectors/association.hpp"
#include "detectors/landmark_radius.hpp"
#include "detectors/scan_detector.hpp"
#include "detectors/sequence_detector.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::detectors {

/// An arc kept for the joint radius: its points and free circle (sensor frame) and the pose.
struct KeptArc {
  ArcObservation arc;
  Pose2 viewpoint;
};

/// The detections of one stop, as they come.
struct StopBlock {
  std::size_t stop = 0;
  const std::vector<io::Scan>* loaded = nullptr;  // the stop's scans as loaded, in order
  std::vector<ScanDetections> scans;
  std::vector<Pose2> viewpoints;
  // per scan, per detection (when collected)
  std::vector<std::vector<std::vector<Eigen::Vector2d>>> arcs;
};

/// The stop of scan i (non-decreasing in i): a vector's entries, or a sequence's stops.
using StopOf = std::function<std::size_t(std::size_t)>;

/// The scans of a sequence: how many, how to load one, and the stop of each.
struct ScanSource {
  std::size_t count;
  const ScanLoader& load;
  const StopOf& stop_of;
};

/// What one pass over the scans detects with.
struct PassSetup {
  const DetectionConfig& base;
  const std::vector<RadiusHint>& hints_world;  ///< radius hints, world frame
  bool collect_arcs;                           ///< keep each detection's arc
};

/// Detects every scan with `pass.base` (plus the hints), stop by stop, and hands each stop's
/// detections to `on_stop` once its last scan is done; on_scan(i) after scan i. Only one stop
/// and one window of scans ahead are in memory.
void detectByStop(const ScanSource& source, const PassSetup& pass, int threads,
                  const std::function<void(StopBlock&)>& on_stop,
                  const std::function<void(std::size_t)>& on_scan);

/// One stop's block through the association: stage 1 into `clusters` (cluster_of per
/// detection), then the linker; folds the tracks into `print` and returns each cluster's track.
std::vector<TrackSerial> linkBlock(const StopBlock& block, const AssociationConfig& cfg,
                                   StopLinker& linker, std::uint64_t& print, StopClusters& clusters,
                                   std::vector<std::vector<int>>& cluster_of);

/// Distinct stops among the first scan_count scans (stop_of non-decreasing).
std::size_t countStops(std::size_t scan_count, const StopOf& stop_of);

/// Continuous motion: at least min_stops stops and more than half of them of one scan.
bool continuousStops(std::size_t scan_count, const StopOf& stop_of, int min_stops);

}  // namespace lidarcal::detectors
