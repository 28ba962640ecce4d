// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One scan of a sequence: a PCD file in the sensor frame with the commanded pose in VIEWPOINT.
// The contract is docs/FORMAT.md. Loading and saving go through PCL's PCDReader/PCDWriter;
// the header is checked first so that errors can name the field at fault.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "common/pose2.hpp"

namespace lidarcal::io {

/// What the header of a scan file says (read without loading the points).
struct ScanHeader {
  /// The file. A string, not a std::filesystem::path: a sequence keeps one header per scan,
  /// and a path also allocates its list of components (about 0.3 KB more per scan).
  std::string path;
  /// The file name without its directory.
  std::string name() const { return std::filesystem::path(path).filename().string(); }
  Pose2 viewpoint;             ///< commanded pose from VIEWPOINT (yaw only)
  std::size_t points = 0;      ///< POINTS (= WIDTH x HEIGHT)
  bool has_intensity = false;  ///< an `intensity` field is present
  bool has_label = false;      ///< a `label` field is present
  bool binary = false;         ///< DATA binary or binary_compressed
};

/// What `lidarcal correct` did to a point: the `correction` field of a corrected scan
/// (docs/FORMAT.md).
enum class PointCorrection : std::uint8_t {
  no_return = 0,     ///< no return (NaN): none in the raw scan, dropped or without a distance
  corrected = 1,     ///< inside the range the model was fitted over: the fit's correction
  extrapolated = 2,  ///< beyond the fitted range: the model continued past its edge
  raw = 3,           ///< beyond the fitted range and left as read (`--outside keep`)
};

/// One scan: points in beam order (NaN = no return), optional intensity and label per point.
struct Scan {
  std::string name;                            ///< file name without directory
  Pose2 viewpoint;                             ///< commanded pose of the sensor
  pcl::PointCloud<pcl::PointXYZI>::Ptr cloud;  ///< points; intensity 0 when absent
  bool has_intensity = false;                  ///< write/read an `intensity` field
  std::vector<std::uint32_t> labels;           ///< per-point label; empty = no `label` field
  /// Per-point correction (corrected scans); empty = no `correction` field.
  std::vector<PointCorrection> correction;
  /// Per-point standard error of the correction, metres (NaN where none); empty = no
  /// `correction_se` field. Written only together with `correction`.
  std::vector<float> correction_se;
};

/// PCD encoding used when writing.
enum class PcdEncoding { binary, ascii };

/// Reads and checks the header of a scan file. Throws InputError naming the file and field.
ScanHeader readScanHeader(const std::filesystem::path& file);

/// Reads a scan file (ASCII, binary or binary_compressed). Throws InputError on bad input.
Scan readScan(const std::filesystem::path& file);

/// Writes a scan atomically (temporary file + rename). Fields: x y z [intensity] [label]
/// [correction correction_se].
void writeScan(const std::filesystem::path& file, const Scan& scan,
               PcdEncoding encoding = PcdEncoding::binary);

/// Viewpoint quaternion (w, z) of a yaw angle, as stored in VIEWPOINT `tx ty 0 qw 0 0 qz`.
void yawToQuaternion(double yaw_rad, double& qw, double& qz);

}  // namespace lidarcal::io
