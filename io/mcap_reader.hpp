// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A small reader of MCAP files (https://mcap.dev/spec), the default storage of ROS 2 bags since
// Iron: no C++ MCAP library is packaged for Debian 12. It reads the data section record by
// record (Header, Schema, Channel, Message, Chunk; index and summary records and unknown opcodes
// are skipped), decompresses chunks (no compression, zstd, lz4 frame) with Debian's libzstd and
// liblz4 one at a time, and hands the messages on in log-time order.
//
// Every length is checked against the bytes that remain (in the file, the chunk or the record)
// before anything is read or allocated; a chunk's uncompressed size is capped (kMaxChunkBytes
// and 1024 times its compressed size). Bad input is an InputError naming the file, the record
// (opcode and byte offset) and what is wrong; nothing else is thrown.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace lidarcal::io {

/// A channel (topic) of an MCAP file with its schema.
struct McapChannel {
  std::uint16_t id = 0;          ///< channel id
  std::string topic;             ///< e.g. /scan
  std::string message_encoding;  ///< e.g. cdr (ROS 2)
  /// e.g. sensor_msgs/msg/LaserScan; empty when the channel has no schema
  std::string schema_name;
  std::size_t messages = 0;     ///< messages on the channel in the data section
  std::uint16_t schema_id = 0;  ///< the Schema record's id (0: none)
  std::string schema_encoding;  ///< e.g. ros2msg; empty when the channel has no schema
  std::string schema_data;      ///< the schema's definition, as recorded
  /// the channel's metadata map as recorded (MCAP Map bytes, length prefix included)
  std::string metadata;
};

/// One message handed on; `data` is valid during the callback only.
struct McapMessage {
  const McapChannel* channel = nullptr;
  std::uint64_t log_time_ns = 0;      ///< log_time, nanoseconds
  std::uint64_t publish_time_ns = 0;  ///< publish_time, nanoseconds
  std::uint32_t sequence = 0;         ///< the Message record's sequence number
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};
using McapMessageCallback = std::function<bool(const McapMessage&)>;

/// Largest uncompressed chunk accepted, bytes (1 GiB).
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;

class McapReader {
 public:
  /// Opens `file` and reads its data section once (each chunk decompressed in turn) to learn the
  /// channels, their message counts and the time span of every chunk. Throws InputError for a
  /// file that is not MCAP, is cut short (no Footer) or is damaged.
  explicit McapReader(const std::filesystem::path& file);
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  /// The channels in the order their Channel records come.
  const std::vector<McapChannel>& channels() const { return channels_; }
  /// The contents of the Metadata records outside chunks (name and map, as recorded), in file
  /// order.
  const std::vector<std::string>& metadataRecords() const;

  /// Hands on the messages of the channels on `topics` in log-time order (equal times in file
  /// order), until `on_message` returns false. Chunks whose times overlap are merged; only those
  /// that hold a message due next are decompressed, so memory stays that of the overlapping
  /// chunks. Returns false when stopped.
  bool forEachMessage(const std::set<std::string>& topics,
                      const McapMessageCallback& on_message) const;

  struct Impl;  ///< the open file and where its messages are (mcap_reader.cpp)

 private:
  std::vector<McapChannel> channels_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lidarcal::io
