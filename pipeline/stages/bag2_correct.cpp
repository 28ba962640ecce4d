// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/bag2_correct.hpp"

#include "common/errors.hpp"
#include "io/import_rosbag2.hpp"
#include "io/rosbag2_rewrite.hpp"
#include "pipeline/stages/bag_correct.hpp"

namespace lidarcal::pipeline {

namespace fs = std::filesystem;

SensorFacts rosbag2SensorFacts(const fs::path& bag, const std::string& topic) {
  return firstScanFacts(bag, topic, io::readRosbag2);
}

CorrectionStats correctRosbag2(const fs::path& in, const fs::path& out, const std::string& topic,
                               const CalibrationModel& model,
                               const calibration::ReadingCorrector& correct,
                               const fs::path& model_file) {
  return correctBagRanges(in, out, BagCorrection{topic, model, correct, model_file},
                          io::rewriteRosbag2);
}

void checkBagOutputKind(const fs::path& in, const fs::path& out, bool ros1) {
  std::error_code ec;
  const std::string ext = out.extension().string();
  const bool dir = !ros1 && fs::is_directory(in, ec);
  const std::string want = ros1 ? ".bag" : dir ? "" : in.extension().string();
  const bool ros2_name = ext == ".mcap" || ext == ".db3";
  if (ros1 && ros2_name)
    throw InputError(out.string(), "--out",
                     "is a ROS 2 bag name, but " + in.string() +
                         " is a ROS1 bag: lidarcal writes a corrected bag in the input's format",
                     "write -o OUT.bag, then convert it to ROS 2 with a bag converter (e.g. the "
                     "rosbags package's rosbags-convert)");
  if (!ros1 && ext == ".bag")
    throw InputError(out.string(), "--out",
                     "is a ROS1 bag name, but " + in.string() +
                         " is a ROS 2 bag: lidarcal writes a corrected bag in the input's format",
                     dir ? "name an output directory (e.g. -o OUT_DIR)"
                         : "write -o OUT" + in.extension().string());
  if (!ros1 && dir && ros2_name)
    throw InputError(out.string(), "--out",
                     "is a file name, but " + in.string() + " is a rosbag2 directory",
                     "name an output directory (e.g. -o OUT_DIR)");
  if (!ros1 && !dir && ext != want && (want == ".mcap" || want == ".db3"))
    throw InputError(out.string(), "--out",
                     "does not end in " + want + " like " + in.string() +
                         " (the output keeps the input's storage)",
                     "write -o OUT" + want);
}

}  // namespace lidarcal::pipeline
