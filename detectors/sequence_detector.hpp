#pragma once
// A whole sequence: detect in every scan (streaming, one scan in memory at a time), associate
// across stops, and, when the landmark radius is not known, estimate it jointly per landmark and
// detect again with that radius fixed (a second pass over the scans). This is the in-process API the calibration
// stage calls; `lidarcal detect` adds the labelled files.

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "detectors/association.hpp"
#include "detectors/scan_detector.hpp"
#include "io/sequence.hpp"

namespace lidarcal::detectors {

struct SequenceDetectionConfig {
  DetectionConfig detection;      ///< per-scan detection; landmark_radius_m overrides sequence.json
  AssociationConfig association;  ///< across stops
  /// Use sequence.json `landmark_radius_m` when detection.landmark_radius_m is unset. Default true.
  bool use_sequence_radius = true;
  /// With the radius estimated: when every landmark's radius lies within this fraction of their
  /// median, the second pass fits clusters near no known landmark with that common radius
  /// (landmarks of one make). Default 0.15.
  double common_radius_tolerance = 0.15;

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
  std::vector<ScanDetections> scans;  ///< per scan in sequence order (scan_index, stop set)
  std::vector<Pose2> viewpoints;      ///< commanded pose of each scan
  Association association;            ///< landmarks and the id of every detection
  RadiusSource radius_source = RadiusSource::none;  ///< how radii were obtained
  std::optional<double> known_radius_m;  ///< the known radius, when radius_source is known
  std::optional<double> common_radius_m;  ///< common radius used in the second pass, when the estimates agreed
  std::size_t radius_failures = 0;    ///< landmarks whose joint radius could not be estimated (free fits kept)
  std::string note;                   ///< plain-language summary (e.g. why no landmark was found)
};

/// Loads scan i of a sequence (0 <= i < scan count).
using ScanLoader = std::function<io::Scan(std::size_t)>;

/// Progress callback: `done` scans processed out of `total` (2 x scans when the radius is
/// estimated: the scans are read a second time with the estimated radii).
using ProgressCallback = std::function<void(std::size_t done, std::size_t total)>;

/// Runs detection and association over `scan_count` scans obtained from `load`; stop_of_scan[i]
/// is the stop of scan i. With the radius unknown: free-radius detection, association, joint
/// radius per landmark, then a second detection pass with those radii and a fresh association.
SequenceDetections detectSequence(std::size_t scan_count, const ScanLoader& load,
                                  const std::vector<std::size_t>& stop_of_scan, const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan = {});

/// The same over a sequence directory (io::readScan per scan, radius from sequence.json).
SequenceDetections detectSequence(const io::Sequence& sequence, const SequenceDetectionConfig& config,
                                  const ProgressCallback& on_scan = {});

/// Labels of one scan: 0 background, the landmark id on the inliers of each associated detection.
std::vector<std::uint32_t> scanLabels(const SequenceDetections& result, std::size_t scan, std::size_t points);

}  // namespace lidarcal::detectors
