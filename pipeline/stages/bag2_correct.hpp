// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// `lidarcal correct IN --model model.json --out OUT` for ROS 2 bags (IN a .mcap or .db3 file, or
// a rosbag2 directory): the bag copied with the ranges of one LaserScan topic corrected by the
// rule of corrected ROS1 bags and the live nodes (correctLaserRanges,
// pipeline/stages/bag_correct.hpp).

#include <filesystem>
#include <string>

#include "calibration/filtering.hpp"
#include "common/calibration_model.hpp"
#include "pipeline/stages/stages.hpp"

namespace lidarcal::pipeline {

/// What the first LaserScan of the ROS 2 bag's topic says about the sensor, for
/// checkModelFitsSensor.
SensorFacts rosbag2SensorFacts(const std::filesystem::path& bag, const std::string& topic);

/// Writes `out` (a new file for a file, an existing empty directory for a directory; the caller
/// makes it atomic) from `in`; refuses a message whose beam count differs from the model's
/// (InputError naming the message).
CorrectionStats correctRosbag2(const std::filesystem::path& in, const std::filesystem::path& out,
                               const std::string& topic, const CalibrationModel& model,
                               const calibration::ReadingCorrector& correct,
                               const std::filesystem::path& model_file);

/// Throws InputError (exit 2) when the output's kind does not fit the input's: a ROS1 bag gives a
/// .bag, a .mcap a .mcap, a .db3 a .db3, a rosbag2 directory a directory (lidarcal does not
/// convert between ROS1 and ROS 2 bags). `ros1` says which the input is.
void checkBagOutputKind(const std::filesystem::path& in, const std::filesystem::path& out,
                        bool ros1);

}  // namespace lidarcal::pipeline
