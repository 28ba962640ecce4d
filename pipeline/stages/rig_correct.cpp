// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/rig_correct.hpp"

#include <algorithm>
#include <map>
#include <memory>

#include "common/errors.hpp"
#include "io/rosbag2_rewrite.hpp"
#include "io/rosbag_rewrite.hpp"
#include "pipeline/stages/bag2_correct.hpp"
#include "pipeline/stages/bag_correct.hpp"

namespace lidarcal::pipeline {

std::vector<std::size_t> rigBlocksForBag(const io::RigModel& model,
                                         const std::filesystem::path& model_file,
                                         const std::vector<std::string>& bag_topics,
                                         const std::vector<std::string>& keys) {
  std::vector<std::size_t> blocks;
  const auto inBag = [&](const std::string& t) {
    return std::find(bag_topics.begin(), bag_topics.end(), t) != bag_topics.end();
  };
  for (const std::string& key : keys) {
    const auto k = model.find(key);
    if (!k)
      throw InputError(model_file.string(), "sensors", "has no block for '" + key + "'",
                       "name a sensor, topic or frame it holds");
    if (!inBag(model.sensors[*k].topic))
      throw InputError(model_file.string(), "sensors[" + std::to_string(*k) + "].topic",
                       "'" + model.sensors[*k].topic + "' is not a LaserScan topic of the bag",
                       "pick a block whose topic it holds");
    if (std::find(blocks.begin(), blocks.end(), *k) == blocks.end()) blocks.push_back(*k);
  }
  if (keys.empty())
    for (std::size_t k = 0; k < model.sensors.size(); ++k)
      if (!model.sensors[k].topic.empty() && inBag(model.sensors[k].topic)) blocks.push_back(k);
  if (blocks.empty())
    throw InputError(
        model_file.string(), "sensors",
        "none of its sensors' topics is a LaserScan topic of the bag",
        "correct a bag of the calibrated vehicle, or pick a block with --sensor and --topic");
  return blocks;
}

std::vector<RigCorrection> correctRigRosbag(const std::filesystem::path& in,
                                            const std::filesystem::path& out,
                                            const RigBagCorrection& c,
                                            std::vector<std::string>& warnings) {
  const io::RigModel& model = c.model;
  const std::filesystem::path& model_file = c.model_file;
  const std::vector<std::size_t>& blocks = c.blocks;
  const calibration::Outside outside = c.outside;
  const bool ros2 = c.ros2;
  std::vector<RigCorrection> done;
  std::vector<std::unique_ptr<MemoCorrector>> memos;
  std::map<std::string, std::size_t> by_topic;
  std::vector<std::string> topics;
  for (const std::size_t k : blocks) {
    const io::RigModelSensor& s = model.sensors[k];
    const std::string where = model_file.string() + " (sensor " + s.name + ")";
    const SensorFacts facts = ros2 ? rosbag2SensorFacts(in, s.topic) : bagSensorFacts(in, s.topic);
    if (const std::string w = checkModelFitsSensor(s.model, facts, where, c.force, outside);
        !w.empty())
      warnings.push_back(w);
    memos.push_back(
        std::make_unique<MemoCorrector>(modelCorrector(s.model, c.method, outside, where)));
    by_topic[s.topic] = done.size();
    done.push_back(RigCorrection{s.name, s.topic, {}});
    topics.push_back(s.topic);
  }
  const io::TopicRangesCallback on_scan = [&](const std::string& topic, std::vector<float>& ranges,
                                              const io::RawScan& scan) {
    const std::size_t i = by_topic.at(topic);
    const io::RigModelSensor& s = model.sensors[blocks[i]];
    checkModelBeams(
        s.model, ranges.size(),
        in.string() + " (" + topic + " LaserScan " + std::to_string(scan.source_index) + ")",
        model_file);
    correctLaserRanges(ranges, scan.range_min_m, scan.range_max_m, *memos[i], done[i].stats);
    ++done[i].stats.scans;
  };
  if (ros2)
    io::rewriteRosbag2Topics(in, out, topics, on_scan);
  else
    io::rewriteRosbagTopics(in, out, topics, on_scan);
  return done;
}

}  // namespace lidarcal::pipeline
