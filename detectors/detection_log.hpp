// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The detections of a sequence's final pass, written to an anonymous temporary file.
// A sequence detected without keeping its scans (memory flat in the sequence's length) is
// visited again scan by scan for the labelled files and the sightings; reading these records
// back replaces detecting every scan a second time. Each record carries a fingerprint of the
// scan's points, so that a visit can refuse scans that changed in between.

#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "detectors/association.hpp"
#include "detectors/scan_detector.hpp"

namespace lidarcal::detectors {

class DetectionLog {
 public:
  /// An empty log in an anonymous temporary file (std::tmpfile, removed when closed); nullptr
  /// when none can be created (then the caller detects again instead).
  static std::shared_ptr<DetectionLog> create();
  ~DetectionLog();
  DetectionLog(const DetectionLog&) = delete;
  DetectionLog& operator=(const DetectionLog&) = delete;

  /// Appends one scan: its detections, the track of each detection (0: none) and the
  /// fingerprint of its points. False when the file cannot be written (disk full, a file-size
  /// limit): the log is then incomplete and must not be read.
  [[nodiscard]] bool append(const ScanDetections& scan, const std::vector<TrackSerial>& tracks,
                            std::uint64_t points_print);
  /// Writes out what is buffered; false when it cannot be (the log must not be read then).
  [[nodiscard]] bool finish();
  /// Starts reading at the first record (after finish()).
  void rewind();
  /// Reads the next record into the arguments; false after the last. Throws InputError when the
  /// file cannot be read back.
  bool next(ScanDetections& scan, std::vector<TrackSerial>& tracks, std::uint64_t& points_print);

 private:
  explicit DetectionLog(std::FILE* file) : file_(file) {}
  std::FILE* file_;
};

/// Fingerprint of a cloud's points: FNV-1a over the count and the coordinates (32-bit words).
std::uint64_t pointsPrint(const pcl::PointCloud<pcl::PointXYZI>& cloud);

}  // namespace lidarcal::detectors
