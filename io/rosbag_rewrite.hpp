// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A ROS1 bag copied message by message, with the ranges of one sensor_msgs/LaserScan topic
// changed by the caller (`lidarcal correct IN.bag --out OUT.bag`). Same connections (topic,
// type, connection header), same messages in the same (time) order with the same time stamps;
// only the `ranges` of the chosen topic's messages differ. Through Debian's rosbag_storage like
// the importer (io/import_rosbag.hpp); throws InputError saying how to enable it otherwise.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "io/import.hpp"

namespace lidarcal::io {

/// Receives the ranges of one LaserScan (metres, as the message holds them) to change in place;
/// `scan` is the message as the importer reads it (angles, limits, stamp), for checks.
using RangesCallback = std::function<void(std::vector<float>& ranges_m, const RawScan& scan)>;

/// The same with the message's topic, for a rewrite of several topics.
using TopicRangesCallback = std::function<void(const std::string& topic,
                                               std::vector<float>& ranges_m, const RawScan& scan)>;

struct BagRewriteReport {
  std::string topic;         ///< the (first) LaserScan topic whose ranges went through the callback
  std::size_t messages = 0;  ///< messages written (all topics)
  std::size_t connections = 0;  ///< connections of the input (each written with its header)
  std::size_t scans = 0;        ///< LaserScan messages passed to the callback
};

/// Writes `out` (a new file; the caller makes it atomic) from `in`. `topic` empty = the bag's
/// only LaserScan topic (as readRosbag). Throws InputError for an unreadable bag or topic.
BagRewriteReport rewriteRosbag(const std::filesystem::path& in, const std::filesystem::path& out,
                               const std::string& topic, const RangesCallback& on_scan);

/// The same for the ranges of every topic in `topics` (each checked as `topic` above; several
/// sensors of one vehicle, each with its own model).
BagRewriteReport rewriteRosbagTopics(const std::filesystem::path& in,
                                     const std::filesystem::path& out,
                                     const std::vector<std::string>& topics,
                                     const TopicRangesCallback& on_scan);

}  // namespace lidarcal::io
