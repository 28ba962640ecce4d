// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The storage of a ROS 2 bag: a single .mcap file, a single .db3 file (SQLite), or a rosbag2
// directory (metadata.yaml naming the storage and its files, read in the order listed). Gives
// the topics with their types and message counts, and the serialised messages of chosen topics
// in time order, file after file. No message decoding here (io/ros2_msgs.hpp does that).
//
// .db3: tables topics(id, name, type, serialization_format, ...) and messages(id, topic_id,
// timestamp, data), read with Debian's libsqlite3 opened read-only. .mcap: io/mcap_reader.hpp.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "io/bag_scans.hpp"

namespace lidarcal::io {

/// A topic of a ROS 2 bag.
struct Rosbag2Topic {
  BagTopic topic;        ///< name, type (e.g. sensor_msgs/msg/LaserScan), messages (over all files)
  std::string encoding;  ///< serialisation format, e.g. cdr
};

/// One serialised message; `data` is valid during the callback only.
struct Rosbag2Message {
  const std::string* topic = nullptr;
  std::int64_t time_ns = 0;  ///< receive (log) time, nanoseconds
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};
using Rosbag2MessageCallback = std::function<bool(const Rosbag2Message&)>;

/// One storage file (.mcap or .db3).
class Rosbag2File {
 public:
  virtual ~Rosbag2File() = default;
  virtual std::vector<Rosbag2Topic> topics() const = 0;
  /// Messages of `topics` in time order; returns false when the callback stopped it.
  virtual bool forEach(const std::set<std::string>& topics,
                       const Rosbag2MessageCallback& on_message) const = 0;
};

class Rosbag2 {
 public:
  /// Opens `bag`: a .mcap or .db3 file (recognised by content) or a rosbag2 directory. Throws
  /// InputError naming the file, the metadata entry or the table when it cannot be read.
  explicit Rosbag2(const std::filesystem::path& bag);
  /// The topics of every file merged by name (counts summed), sorted by name.
  const std::vector<Rosbag2Topic>& topics() const { return topics_; }
  std::vector<BagTopic> bagTopics() const;
  /// Messages of `topics`, in time order within each file, file after file.
  void forEach(const std::set<std::string>& topics, const Rosbag2MessageCallback& on_message) const;

 private:
  std::vector<std::unique_ptr<Rosbag2File>> files_;
  std::vector<Rosbag2Topic> topics_;
};

/// What metadata.yaml says about the storage (only the entries lidarcal needs).
struct Rosbag2Metadata {
  std::string storage_identifier;                ///< sqlite3 or mcap
  std::vector<std::string> relative_file_paths;  ///< the storage files, in order
  std::string compression_format;                ///< empty when not compressed
  std::string compression_mode;                  ///< empty, FILE or MESSAGE
};
/// Parses the block-style YAML rosbag2 writes (`key: value`, `- item` lists). Throws InputError
/// (naming `file`) when storage_identifier or relative_file_paths is missing.
Rosbag2Metadata parseRosbag2Metadata(const std::string& text, const std::string& file);

}  // namespace lidarcal::io
