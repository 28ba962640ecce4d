// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Detection and association measured against a simulator's truth (truth.json, true_ranges.csv).
// Used by `lidarcal detect --truth` and bench/eval_detection; never by detection itself.
//
// Definitions (docs/results/detection.md):
//  - a detection's truth is the target (kind, id) of the majority of its inlier beams;
//    it is a true positive when that target is a landmark;
//  - an observation (scan, landmark) is observable when at least min_beams of the landmark's
//    beams have a return and the landmark is not partly hidden (its beams form one run and the
//    beams next to the run hit nothing nearer); recall = observable observations with a
//    true-positive detection. Partly hidden observations are counted apart;
//  - each landmark id maps to the truth landmark most of its detections belong to; a detection
//    has a wrong id when its truth differs from its id's landmark (false positives given an id
//    count as wrong ids); purity = 1 - wrong ids / detections with an id;
//  - errors are against the true centre in the frame of the true sensor pose; the range error
//    is also given against f(D - R) + R, the centre range the sensor's own bias f predicts.

#include <cstddef>
#include <vector>

#include "common/truth.hpp"
#include "detectors/association.hpp"
#include "detectors/scan_detector.hpp"
#include "io/true_ranges.hpp"

namespace lidarcal::detectors {

struct EvaluationConfig {
  int min_beams = 3;  ///< returns on a landmark that make an observation observable. Default 3
  /// bins of true centre range, metres
  std::vector<double> range_edges_m{0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0};
};

/// The truth of one scan.
struct ScanTruth {
  std::vector<io::TrueRange> beams;  ///< one row per point of the scan, in point order
  std::vector<bool> returned;        ///< the point has a return (finite x, y)
  Pose2 sensor;                      ///< true pose of the sensor frame (actual pose + mount yaw)
};

/// Errors of true-positive detections whose true centre range falls in [lo_m, hi_m).
struct RangeBin {
  double lo_m = 0.0, hi_m = 0.0;    ///< bin edges, metres
  std::size_t observable = 0;       ///< observable observations in the bin
  std::size_t detected = 0;         ///< of which detected
  std::size_t detections = 0;       ///< true-positive detections in the bin
  double centre_rms_m = 0.0;        ///< RMS |centre - true centre|, metres
  double bearing_rms_rad = 0.0;     ///< RMS bearing error, radians
  double range_bias_m = 0.0;        ///< mean (range - (f(D - R) + R)), metres
  double range_rms_m = 0.0;         ///< RMS of the same, metres
  std::size_t free_radii = 0;       ///< detections with a free-radius fit
  double free_radius_bias_m = 0.0;  ///< mean (free radius - true radius), metres
  double free_radius_rms_m = 0.0;   ///< RMS of the same, metres
  double radius_bias_m = 0.0;       ///< mean (reported radius - true radius), metres
};

struct DetectionEvaluation {
  std::size_t scans = 0;            ///< scans evaluated
  std::size_t detections = 0;       ///< detections evaluated (with an id only, when ids were given)
  std::size_t true_positives = 0;   ///< detections on a landmark
  std::size_t false_positives = 0;  ///< detections on anything else
  std::size_t false_on_clutter = 0;        ///< of which on clutter cylinders
  std::size_t false_on_walls = 0;          ///< of which on walls
  std::size_t observable = 0;              ///< observable (scan, landmark) pairs
  std::size_t detected = 0;                ///< of which detected
  std::size_t partly_hidden = 0;           ///< pairs with min_beams returns but partly hidden
  std::size_t partly_hidden_detected = 0;  ///< of which detected anyway
  double precision = 0.0;                  ///< true_positives / detections (1 when there is none)
  double recall = 0.0;                     ///< detected / observable (1 when nothing is observable)
  std::size_t with_id = 0;                 ///< detections with a landmark id
  std::size_t wrong_id = 0;                ///< of which with the wrong id
  double purity = 1.0;                     ///< 1 - wrong_id / with_id
  std::size_t ids = 0;                     ///< landmark ids in the association
  std::size_t split_ids = 0;     ///< ids mapping to a truth landmark another id already maps to
  std::vector<int> truth_of_id;  ///< truth landmark (1-based, 0: none) of each id (index id - 1)
  std::vector<RangeBin> bins;    ///< errors by true range
};

/// Builds the truth of scan `scan_index` from the truth file, its true ranges and the scan's cloud.
ScanTruth makeScanTruth(const Truth& truth, std::size_t scan_index,
                        std::vector<io::TrueRange> beams,
                        const pcl::PointCloud<pcl::PointXYZI>& cloud);

/// Evaluates detections (all of them when `association` is null, else only those given an id).
DetectionEvaluation evaluateDetections(const std::vector<ScanDetections>& scans,
                                       const Association* association,
                                       const std::vector<ScanTruth>& truth,
                                       const Truth& scene_truth,
                                       const EvaluationConfig& config = {});

}  // namespace lidarcal::detectors
