#pragma once
// `lidarcal import`: a recording (ROS1 bag, CARMEN log, YDLIDAR X4 .dat, CSV) streamed scan by
// scan into a PCD scan sequence. Composition of an io importer and io::SequenceWriter.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "io/import.hpp"
#include "io/import_carmen.hpp"
#include "io/sequence_writer.hpp"

namespace lidarcal::pipeline {

enum class ImportFormat { rosbag1, carmen, ydlidar, csv };

/// Parses "rosbag1", "carmen", "ydlidar" or "csv"; throws InputError otherwise.
ImportFormat parseImportFormat(const std::string& name);
const char* toString(ImportFormat format);

struct ImportSettings {
  ImportFormat format = ImportFormat::csv;   ///< what the input is
  std::filesystem::path input;               ///< the recording (read only)
  std::filesystem::path out;                 ///< the sequence directory to create
  io::SequenceWriterConfig writer;           ///< --every, --max-scans, --overwrite, encoding
  std::string topic;                         ///< rosbag1: LaserScan topic; empty = the only one
  io::CarmenPose carmen_pose = io::CarmenPose::corrected;  ///< carmen: pose written to VIEWPOINT
  std::optional<double> range_min_m;         ///< overrides the format's lower range limit, metres
  std::optional<double> range_max_m;         ///< overrides the format's upper range limit, metres
  std::string sensor_name;                   ///< sensor_name for sequence.json; empty = what the input says
};

struct ImportResult {
  io::ImportReport read;               ///< what the importer read
  io::SequenceWriteSummary written;    ///< what was written
};

/// Imports settings.input into settings.out. `on_progress` (optional) receives the fraction of
/// the input read, 0..1. Nothing appears at settings.out unless the whole import succeeds.
/// Throws InputError for bad input or options.
ImportResult importRecording(const ImportSettings& settings, const std::function<void(double)>& on_progress = {});

}  // namespace lidarcal::pipeline
