// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A ROS 2 bag copied message by message with the ranges of one or more sensor_msgs/msg/LaserScan
// topics changed by the caller (`lidarcal correct IN.mcap|IN.db3|IN_DIR --out OUT`): the ROS 2
// counterpart of io/rosbag_rewrite.hpp, with no ROS library.
//
// - .mcap: every Schema, Channel and Metadata record and every message (channel, sequence,
//   log and publish times, bytes) written again by io::McapWriter in log-time order, chunks
//   compressed with zstd; only the bytes of the chosen topics' ranges differ.
// - .db3: the SQLite file copied, then each of the chosen topics' messages updated in place: every
//   other row, table and byte of the messages is the input's.
// - rosbag2 directory: metadata.yaml copied as it is and each storage file it lists rewritten
//   as above, under the same name.
// A message's ranges are patched in its own CDR bytes (same byte order, same size).

#include <filesystem>
#include <string>
#include <vector>

#include "io/rosbag_rewrite.hpp"

namespace lidarcal::io {

/// Writes `out` from `in` (a .mcap or .db3 file: `out` a new file; a rosbag2 directory: `out` an
/// existing empty directory; the caller makes either atomic). `topic` empty = the bag's only
/// LaserScan topic. Throws InputError for an unreadable bag, topic or message.
BagRewriteReport rewriteRosbag2(const std::filesystem::path& in, const std::filesystem::path& out,
                                const std::string& topic, const RangesCallback& on_scan);

/// The same for the ranges of every topic in `topics` in one pass (each checked as `topic`
/// above; several sensors of one vehicle, each with its own model). The callback is told each
/// message's topic; messages reach it in time order.
BagRewriteReport rewriteRosbag2Topics(const std::filesystem::path& in,
                                      const std::filesystem::path& out,
                                      const std::vector<std::string>& topics,
                                      const TopicRangesCallback& on_scan);

}  // namespace lidarcal::io
