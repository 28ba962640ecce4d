// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// `lidarcal correct IN.bag|IN.mcap|IN.db3|IN_DIR --model RIG_MODEL.json --out OUT`: a ROS1 or
// ROS 2 bag of several lidars with each LaserScan topic corrected by its own sensor's block of a
// rig model (io/rig_model_io.hpp), each block checked against its topic as a single-sensor model
// is against the bag's one.

#include <filesystem>
#include <string>
#include <vector>

#include "io/rig_model_io.hpp"
#include "pipeline/stages/stages.hpp"

namespace lidarcal::pipeline {

struct RigCorrection {
  std::string sensor, topic;  ///< the block and the topic it corrected
  CorrectionStats stats;      ///< its returns
};

/// The blocks to apply: every block whose topic the bag holds, or those `keys` name (sensor name,
/// topic or frame). Throws InputError naming the model file when a key names no block, a block
/// has no topic, or no block's topic is in the bag.
std::vector<std::size_t> rigBlocksForBag(const io::RigModel& model,
                                         const std::filesystem::path& model_file,
                                         const std::vector<std::string>& bag_topics,
                                         const std::vector<std::string>& keys);

/// The blocks of a rig model applied to a bag, and how.
struct RigBagCorrection {
  const io::RigModel& model;
  const std::filesystem::path& model_file;  ///< named in errors
  const std::vector<std::size_t>& blocks;   ///< rigBlocksForBag
  calibration::InversionMethod method;
  calibration::Outside outside;
  bool force = false;  ///< apply a model whose range limits differ, with a warning
  bool ros2 = false;   ///< the bag is a ROS 2 bag
};

/// Writes `out` (a new file, or for a rosbag2 directory an existing empty one; the caller makes it
/// atomic) from `in`, each chosen block's topic corrected by its model in one pass (checked
/// first: status, sensor name, range limits unless `force`; warnings go to `warnings`). Throws
/// InputError or DataError naming the block.
std::vector<RigCorrection> correctRigRosbag(const std::filesystem::path& in,
                                            const std::filesystem::path& out,
                                            const RigBagCorrection& c,
                                            std::vector<std::string>& warnings);

}  // namespace lidarcal::pipeline
