// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// model.json of a rig (docs/FORMAT.md, "Rig model"): one block per sensor, each block a complete
// single-sensor model (format lidarcal-model/1) beside the sensor's name, topic, frame and
// mounting; the sensors' relative mountings with their covariance and their design; the poles,
// the vehicle's stops and what the data could not determine. `correct`, `export` and the nodes
// pick a block by sensor name, topic or frame (readModelFor); single-sensor model.json files are
// read as they always were.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/calibration_model.hpp"
#include "common/rig.hpp"
#include "common/status.hpp"

namespace lidarcal::io {

/// One sensor's block.
struct RigModelSensor {
  std::string name;      ///< short name (the rig sequence's sub-directory)
  std::string topic;     ///< its LaserScan topic (empty when not from a bag)
  std::string frame_id;  ///< its tf frame (empty when unknown)
  /// estimated mounting (vehicle frame; relative frame: the reference at its design)
  Mounting mounting;
  /// row-major 3x3 of (x m, y m, yaw rad); zero when held
  std::array<double, 9> mounting_covariance{};
  bool mounting_held = false;      ///< the relative frame's reference
  std::optional<Mounting> design;  ///< the mounting tf_static gives (first recording), when known
  double beam_scatter_m = 0.0;     ///< tau: a beam's error that repeats from scan to scan, metres
  CalibrationModel model;          ///< the range model, as a single-sensor model.json holds it
};

/// `sensor` seen from `reference`, estimated and designed.
struct RigModelRelative {
  std::string reference, sensor;       ///< sensor names
  Pose2 pose;                          ///< x, y (m), yaw (rad) of `sensor` in `reference`'s frame
  std::array<double, 9> covariance{};  ///< row-major 3x3 of (x, y, yaw)
  std::optional<Pose2> design;         ///< the same from tf_static, when both designs are known
};

/// A pole as calibrated.
struct RigModelPole {
  int id = 0;                             ///< pole id
  double x_m = 0.0, y_m = 0.0;            ///< centre in the frame of the vehicle's poses, metres
  std::array<double, 4> covariance_m2{};  ///< row-major 2x2
  std::vector<std::string> sensors;       ///< the sensors that saw it
};

struct RigModel {
  std::string frame;          ///< "vehicle" or "relative"
  std::string reference;      ///< the reference sensor's name
  std::string vehicle_frame;  ///< the frame the mountings are in (e.g. base_footprint)
  bool scale_free = false;    ///< the common range scale was held (reference alpha_1 = 1)
  bool motion_prior = false;  ///< odometry steps were the vehicle's prior
  double radius_m = 0.0;      ///< pole radius
  std::vector<RigModelSensor> sensors;
  std::vector<RigModelRelative> relative;
  std::vector<RigModelPole> poles;  ///< centres in the frame of the vehicle's poses
  std::vector<Pose2> stops;         ///< the vehicle's refined pose per stop
  std::vector<std::string> notes;   ///< what the data determine and what not
  Status status;                    ///< ok, or why there are no mountings
  /// Index of the block whose name, topic or frame is `key`; nullopt when none.
  std::optional<std::size_t> find(const std::string& key) const;
};

/// True when `file` is a rig model (its format says so); false for any other file.
bool isRigModel(const std::filesystem::path& file);
void writeRigModel(const std::filesystem::path& file, const RigModel& model);
/// Throws InputError naming the field.
RigModel readRigModel(const std::filesystem::path& file);

/// The model of one sensor: a single-sensor model.json as it is (`key` unused), or the block of a
/// rig model whose name, topic or frame is `key`. Throws InputError listing the blocks when `key`
/// is empty or names none. `chosen` (optional) receives the block's name ("" for a single model).
CalibrationModel readModelFor(const std::filesystem::path& file, const std::string& key,
                              std::string* chosen = nullptr);

/// The model a live node applies: a single-sensor model.json as it is; of a rig model, the block
/// `sensor_name` names when it is set, else the block whose topic is `topic` (the node's input,
/// resolved). Throws InputError naming the file and its "sensors", listing the blocks, when no
/// block matches: the node's refusal of a model of another sensor. `chosen` as readModelFor's.
CalibrationModel readModelForNode(const std::filesystem::path& file,
                                  const std::optional<std::string>& sensor_name,
                                  const std::string& topic, std::string* chosen = nullptr);

}  // namespace lidarcal::io
