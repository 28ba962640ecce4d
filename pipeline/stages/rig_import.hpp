// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// `lidarcal import BAG... --topic T1,T2[,...] -o RIG`: several LaserScan topics of one vehicle
// into one rig sequence (io/rig.hpp): one ordinary sequence per sensor, the vehicle's pose and
// stop of every scan (scans.csv), each sensor's designed mounting from /tf_static (rig.json).

#include <functional>
#include <string>
#include <vector>

#include "io/rig.hpp"
#include "pipeline/stages/import.hpp"

namespace lidarcal::pipeline {

struct RigImportSettings {
  ImportSettings base;  ///< format (a bag kind), inputs, out, writer, --pose, range limits
  std::vector<std::string> topics;  ///< the LaserScan topics, one per sensor (two or more)
  /// sensor names, one per topic; empty: from the topics (/scan_front -> scan_front)
  std::vector<std::string> names;
  /// The frame the mountings are given in: "auto" (the frame below the first /tf link above each
  /// scan frame: base_footprint on a ROS vehicle) or a frame name. Default auto.
  std::string vehicle_frame = "auto";
};

struct RigImportResult {
  io::RigMeta meta;                               ///< what rig.json holds
  std::vector<io::SequenceWriteSummary> written;  ///< per sensor
  std::vector<io::ImportReport> read;             ///< per sensor, summed over the recordings
  std::size_t stops = 0;                          ///< the vehicle's stops
  std::vector<std::string> notes;                 ///< facts the user should know
  /// "SENSOR in RECORDING" for each topic of a recording whose stops mostly hold one or two scans
  /// (io::ImportReport::short_stops)
  std::vector<std::string> short_stops;
};

/// Sensor names from topics: the topic without its leading slash, other slashes as '_'.
std::vector<std::string> sensorNamesFromTopics(const std::vector<std::string>& topics);

/// Imports every topic of every recording. Each recording begins a new stop; within one, the
/// vehicle's poses (when --pose gives them) split stops where they move beyond --still-m /
/// --still-deg. Nothing appears at the output unless the whole import succeeds. Throws
/// InputError for bad input or options.
RigImportResult importRig(const RigImportSettings& settings,
                          const std::function<void(double)>& on_progress = {});

}  // namespace lidarcal::pipeline
