// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A rig sequence: the scans of several lidars on one vehicle (docs/FORMAT.md, "Several sensors
// on one vehicle"). A directory holding
//   rig.json      the sensors (name, topic, frame, sub-directory, designed mounting), the frames
//                 and where the vehicle's poses come from, the recordings imported;
//   scans.csv     one row per scan of every sensor: its file, time stamp, recording, the
//                 vehicle's stop and the vehicle's pose;
//   NAME/         one ordinary sequence per sensor (PCD scans + sequence.json): any single-sensor
//                 command reads it as it is.

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/rig.hpp"
#include "io/sequence.hpp"

namespace lidarcal::io {

class JsonView;  // io/json_util.hpp

/// One sensor of a rig sequence.
struct RigSensorInfo {
  std::string name;      ///< short name, unique; also its sub-directory
  std::string topic;     ///< the LaserScan topic it was imported from (empty: not a bag)
  std::string frame_id;  ///< its tf frame (empty when unknown)
  /// designed mounting in the vehicle frame (tf_static), when known
  std::optional<Mounting> mounting;
};

/// One recording imported into the rig, with the mountings its tf_static gave (they may differ
/// from recording to recording when the design was edited between them).
struct RigInput {
  std::string name;  ///< the recording's file name
  /// sensor name -> tf_static mounting in this recording
  std::map<std::string, Mounting> mountings;
};

/// rig.json.
struct RigMeta {
  /// the frame the mountings are in (e.g. base_footprint); empty when unknown
  std::string vehicle_frame;
  /// where the vehicle's poses come from: "tf:FRAME", "odom:TOPIC" or "none"
  std::string pose_source;
  std::vector<RigSensorInfo> sensors;
  std::vector<RigInput> inputs;
  /// Whether scans.csv holds measured vehicle poses (pose_source is not "none").
  bool vehiclePosesKnown() const { return !pose_source.empty() && pose_source != "none"; }
  /// Index of the sensor whose name, topic or frame is `key`; nullopt when none.
  std::optional<std::size_t> find(const std::string& key) const;
};

/// One row of scans.csv.
struct RigScan {
  std::string sensor;     ///< sensor name
  std::string file;       ///< scan file in the sensor's directory
  double stamp_s = 0.0;   ///< time stamp, seconds (NaN when the recording has none)
  std::size_t input = 0;  ///< recording index (rig.json inputs)
  std::size_t stop = 0;   ///< the vehicle's stop, counted over the rig
  Pose2 vehicle;          ///< the vehicle's pose (identity when not recorded)
};

/// An opened rig sequence.
struct Rig {
  std::filesystem::path dir;
  RigMeta meta;
  std::vector<RigScan> scans;       ///< scans.csv, in file order
  std::vector<Sequence> sequences;  ///< per sensor (meta.sensors order)
  /// Index of scan row `row`'s scan within its sensor's sequence (matched by file name).
  std::vector<std::size_t> scan_index;
};

/// True when `dir` holds rig.json.
bool isRigDirectory(const std::filesystem::path& dir);

/// Opens a rig sequence: rig.json, scans.csv and every sensor's sequence. Throws InputError
/// naming the file and field when one is missing or malformed, when scans.csv names a sensor or
/// a scan that does not exist, or a sensor's scan is missing from scans.csv.
Rig openRig(const std::filesystem::path& dir);

/// rig.json and scans.csv (atomically each).
void writeRigMeta(const std::filesystem::path& file, const RigMeta& meta);
void writeRigScans(const std::filesystem::path& file, const std::vector<RigScan>& scans);
RigMeta readRigMeta(const std::filesystem::path& file);
std::vector<RigScan> readRigScans(const std::filesystem::path& file);

/// Index of the entry of `items` (each with name, topic, frame_id) that `key` names by any of
/// them; nullopt when none. RigMeta and RigModel look their sensors up the same way.
template <typename T>
std::optional<std::size_t> findSensorByKey(const std::vector<T>& items, const std::string& key) {
  for (std::size_t s = 0; s < items.size(); ++s)
    if (items[s].name == key || (!items[s].topic.empty() && items[s].topic == key) ||
        (!items[s].frame_id.empty() && items[s].frame_id == key))
      return s;
  return std::nullopt;
}

/// The JSON object of a mounting ({x_m, y_m, yaw_rad, upside_down, z_m}) and back; reading
/// throws InputError naming the field.
nlohmann::ordered_json mountingJson(const Mounting& m);
Mounting readMounting(const JsonView& v);

}  // namespace lidarcal::io
