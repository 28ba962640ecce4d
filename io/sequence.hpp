#pragma once
// A scan sequence: a directory of .pcd files in lexicographic order, grouped into stops by
// their VIEWPOINT, with optional metadata in sequence.json (docs/FORMAT.md).
// Opening a sequence reads headers only; scans are loaded one at a time with readScan().

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/pose2.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::io {

/// Optional metadata of a sequence (sequence.json). Ground truth never lives here.
struct SequenceMeta {
  std::optional<std::string> sensor_name;       ///< free text, e.g. "RPLIDAR A2"
  std::optional<double> landmark_radius_m;      ///< common radius of the landmarks, when known
  std::optional<double> range_min_m;            ///< smallest range the sensor reports
  std::optional<double> range_max_m;            ///< largest range the sensor reports
  std::optional<int> beams;                     ///< beams per scan
};

/// Consecutive scans taken at one commanded pose.
struct Stop {
  Pose2 commanded;                  ///< VIEWPOINT of the stop's first scan
  std::vector<std::size_t> scans;   ///< indices into Sequence::scans, in file order
};

/// Tolerances for "same VIEWPOINT" (docs/FORMAT.md: 1 mm and 0.01 degree).
struct StopTolerance {
  double position_m = 1e-3;               ///< max distance between viewpoints of one stop
  double yaw_rad = 0.01 * 3.14159265358979323846 / 180.0;  ///< max heading difference
};

struct Sequence {
  std::filesystem::path dir;          ///< the sequence directory
  std::vector<ScanHeader> scans;      ///< one per .pcd file, lexicographic order
  std::vector<Stop> stops;            ///< consecutive scans with the same VIEWPOINT
  std::vector<std::size_t> stop_of_scan;  ///< stop index of each scan
  SequenceMeta meta;                  ///< sequence.json, when present
};

/// Groups consecutive viewpoints into stops.
std::vector<Stop> groupStops(const std::vector<Pose2>& viewpoints, const StopTolerance& tol = {});

/// Lists and checks a sequence directory (headers and sequence.json only). Throws InputError
/// when the directory is missing, holds no .pcd file, a header is bad, a scan file ends in
/// `.PCD` (any case but `.pcd`), two names carry one scan number (`scan_1.pcd`, `scan_0001.pcd`)
/// or numbers without zero padding would be read out of order (`scan_10.pcd` before
/// `scan_2.pcd`), or a scan's point count differs from sequence.json `beams`.
Sequence openSequence(const std::filesystem::path& dir, const StopTolerance& tol = {});

/// Fewest and most points in a scan of the sequence (equal when every scan has one beam count).
std::pair<std::size_t, std::size_t> pointCountRange(const Sequence& seq);

/// Reads sequence.json (throws InputError on malformed content).
SequenceMeta readSequenceMeta(const std::filesystem::path& file);
/// Writes sequence.json atomically; absent fields are omitted.
void writeSequenceMeta(const std::filesystem::path& file, const SequenceMeta& meta);

/// Name of scan file `index` in a sequence written by lidarcal: scan_000000.pcd, ...
std::string scanFileName(std::size_t index);

}  // namespace lidarcal::io
