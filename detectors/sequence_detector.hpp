// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A whole sequence: detect in every scan (streaming, the scans of one stop in memory at a
// time), associate across stops, and, when the landmark radius is not known, estimate it
// jointly per landmark and detect again with that radius fixed (a second pass over the scans).
// In the first pass, objects that no single arc of a stop determines (thin far poles, 3-9
// beams) are fitted with the radius of the stop's scans pooled (stop_radius.hpp). This is the
// in-process API the calibration stage calls; `lidarcal detect` adds the labelled files.
//
// Memory. The scans are processed stop by stop: stage 1 of the association (association.hpp)
// needs one stop's detections, the tracking across stops only that stop's clusters and the
// tracks alive. With `keep_scans` false the result holds no per-scan or per-stop data, so memory
// does not grow with the length of the sequence (it grows with the landmarks and the objects
// seen in the last AssociationConfig::forget_after_stops stops; the radius estimate keeps at
// most arcs_per_landmark arcs per track); the final pass's detections go to a temporary file
// (detection_log.hpp), from which forEachScan gives each scan's detections without detecting
// again (and, when no temporary file can be made, by detecting each stop again). Scans are
// loaded and detected a window ahead (16 per thread: SequenceDetectionConfig::threads), so one
// window is in memory besides the current stop.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "detectors/association.hpp"
#include "detectors/scan_detector.hpp"
#include "io/sequence.hpp"

namespace lidarcal::detectors {

class DetectionLog;

struct SequenceDetectionConfig {
  DetectionConfig detection;      ///< per-scan detection; landmark_radius_m overrides sequence.json
  AssociationConfig association;  ///< across stops
  /// Use sequence.json `landmark_radius_m` when detection.landmark_radius_m is unset. Default true.
  bool use_sequence_radius = true;
  /// With the radius estimated: when every landmark's radius lies within this fraction of their
  /// median, the second pass fits clusters near no known landmark with that common radius
  /// (landmarks of one make). Default 0.15.
  double common_radius_tolerance = 0.15;
  /// Keep every scan's detections in the result (SequenceDetections::scans, viewpoints and
  /// association.ids). false: the result stays small whatever the number of scans, and
  /// forEachScan reads them back from a temporary file. Default true.
  bool keep_scans = true;
  /// With the radius estimated: the arcs kept per stop cluster for the joint radius (spread
  /// evenly over its detections), which bounds what the estimate keeps per stop. Default 16.
  std::size_t arcs_per_stop_cluster = 16;
  /// With the radius estimated: the arcs kept per track (an even sample over its stops), which
  /// bounds what the estimate keeps per landmark however long the sequence. Default 1024.
  std::size_t arcs_per_landmark = 1024;
  /// Continuous motion (the robot never stopped: at least continuous_min_stops stops and more
  /// than half of them one scan each, as imports of odometry give): the association's
  /// drift_per_m, the growth of a track's reach per metre travelled since its last sighting
  /// (association.hpp). Stop and go keeps association.drift_per_m. Default 0.2.
  double continuous_drift_per_m = 0.2;
  int continuous_min_stops = 20;  ///< see continuous_drift_per_m. Default 20
  /// Threads detecting scans (a window of scans at a time; each scan's detection is its own, so
  /// the result does not depend on the number). 0: the machine's cores, at most 8. Default 0.
  int threads = 0;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// Where the landmark radius came from.
enum class RadiusSource {
  known,      ///< given (configuration or sequence.json): every centre fitted with it fixed
  estimated,  ///< estimated jointly per landmark, centres refitted with it
  none,       ///< no landmark, nothing to estimate
};
const char* toString(RadiusSource source);

struct SequenceDetections {
  /// Per scan in sequence order (scan_index, stop set); empty unless keep_scans. `clusters` is
  /// left empty: the per-cluster diagnostics of every scan would make memory grow with the
  /// sequence (detectScan has them).
  std::vector<ScanDetections> scans;
  std::vector<Pose2> viewpoints;  ///< commanded pose of each scan (empty unless keep_scans)
  /// landmarks, and the id of every detection (ids: only with keep_scans)
  Association association;
  RadiusSource radius_source = RadiusSource::none;  ///< how radii were obtained
  std::optional<double> known_radius_m;  ///< the known radius, when radius_source is known
  /// common radius used in the second pass, when the estimates agreed
  std::optional<double> common_radius_m;
  /// landmarks whose joint radius could not be estimated (free fits kept)
  std::size_t radius_failures = 0;
  /// the sequence was taken as continuous motion (continuous_drift_per_m used)
  bool continuous = false;
  std::string note;  ///< plain-language summary (e.g. why no landmark was found)

  /// How to run the final pass again (forEachScan without kept scans).
  struct Replay {
    DetectionConfig detection;  ///< the final pass's configuration (radius hints excepted)
    /// estimated radii at their world positions (empty with a known radius)
    std::vector<RadiusHint> hints_world;
    AssociationConfig association;
    TrackIds track_ids;             ///< landmark id of each track of the final pass
    std::uint64_t fingerprint = 0;  ///< of the final pass's tracks at every stop (changed scans)
    int threads = 0;                ///< SequenceDetectionConfig::threads
  } replay;
  /// Without kept scans: the final pass's detections and tracks in a temporary file, which
  /// forEachScan reads instead of detecting again; null when no temporary file could be made.
  /// Copies of the result share the file: visit one of them at a time.
  std::shared_ptr<DetectionLog> log;
};

/// Loads scan i of a sequence (0 <= i < scan count). Called from several threads at once when
/// SequenceDetectionConfig::threads is not 1 (each call for another scan).
using ScanLoader = std::function<io::Scan(std::size_t)>;

/// Progress callback: `done` scans processed out of `total` (2 x scans when the radius is
/// estimated: the scans are read a second time with the estimated radii).
using ProgressCallback = std::function<void(std::size_t done, std::size_t total)>;

/// Runs detection and association over `scan_count` scans obtained from `load`; stop_of_scan[i]
/// is the stop of scan i, non-decreasing (the scans of a stop are consecutive). With the radius
/// unknown: free-radius detection, association, joint radius per landmark, then a second detection
/// pass with those radii and a fresh association.
SequenceDetections detectSequence(std::size_t scan_count, const ScanLoader& load,
                                  const std::vector<std::size_t>& stop_of_scan,
                                  const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan = {});

/// The same over a sequence directory (io::readScan per scan, radius from sequence.json).
SequenceDetections detectSequence(const io::Sequence& sequence,
                                  const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan = {});

/// The same with the scans of `sequence` obtained from `load` (e.g. corrected on the fly).
SequenceDetections detectSequence(const io::Sequence& sequence, const ScanLoader& load,
                                  const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan = {});

/// Receives scan `scan`'s detections of the final pass and their landmark ids (0: none).
using ScanVisitor = std::function<void(std::size_t scan, const ScanDetections& detections,
                                       const std::vector<int>& ids)>;

/// Visits every scan in order with its detections and ids: from the result when the scans were
/// kept, else from the result's log (each scan loaded to check that its points are those
/// detected), else by detecting each stop again with the final configuration (one stop's
/// detections in memory). `scan_count`, `load` and `stop_of_scan` must be those given to
/// detectSequence; throws DataError when the scans changed in between.
void forEachScan(const SequenceDetections& result, std::size_t scan_count, const ScanLoader& load,
                 const std::vector<std::size_t>& stop_of_scan, const ScanVisitor& visit,
                 const ProgressCallback& on_scan = {});

/// The same over a sequence directory.
void forEachScan(const SequenceDetections& result, const io::Sequence& sequence,
                 const ScanVisitor& visit, const ProgressCallback& on_scan = {});

/// The same with the scans obtained from `load` (the loader given to detectSequence).
void forEachScan(const SequenceDetections& result, const io::Sequence& sequence,
                 const detectors::ScanLoader& load, const ScanVisitor& visit,
                 const ProgressCallback& on_scan = {});

/// Receives scan `scan` as loaded, its detections of the final pass and their landmark ids.
using LoadedScanVisitor =
    std::function<void(std::size_t scan, const io::Scan& loaded, const ScanDetections& detections,
                       const std::vector<int>& ids)>;

/// As forEachScan, with each scan loaded once and given to the visitor (a stop's scans when
/// detecting again; otherwise one at a time). Throws DataError when a scan's points are not
/// those detected.
void forEachLoadedScan(const SequenceDetections& result, std::size_t scan_count,
                       const ScanLoader& load, const std::vector<std::size_t>& stop_of_scan,
                       const LoadedScanVisitor& visit, const ProgressCallback& on_scan = {});

/// The same over a sequence directory.
void forEachLoadedScan(const SequenceDetections& result, const io::Sequence& sequence,
                       const LoadedScanVisitor& visit, const ProgressCallback& on_scan = {});

/// Labels of one scan: 0 background, the landmark id on the inliers of each associated detection.
std::vector<std::uint32_t> scanLabels(const ScanDetections& detections, const std::vector<int>& ids,
                                      std::size_t points);

/// The same for scan `scan` of a result whose scans were kept.
std::vector<std::uint32_t> scanLabels(const SequenceDetections& result, std::size_t scan,
                                      std::size_t points);

}  // namespace lidarcal::detectors
