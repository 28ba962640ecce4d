// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A small writer of MCAP files (https://mcap.dev/spec), beside the reader (io/mcap_reader.hpp):
// magic, Header, the Schema and Channel records, Messages in Chunks (zstd through Debian's
// libzstd, or uncompressed; each with the CRC-32 of its records) followed by their MessageIndex
// records, DataEnd, then the summary section (Schemas, Channels, Statistics, ChunkIndexes,
// MetadataIndexes), its SummaryOffset records, the Footer (with the summary's CRC-32) and the
// closing magic, so that readers can seek by the summary as the mcap tools do.
//
// Writes straight to `file` (the caller makes it atomic: io/atomic_file.hpp). Deterministic: the
// same calls give the same bytes.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace lidarcal::io {

enum class McapCompression { none, zstd };

struct McapWriterOptions {
  std::string profile = "ros2";                         ///< Header profile ("ros2" for a ROS 2 bag)
  std::string library = "lidarcal";                     ///< Header library: who wrote the file
  McapCompression compression = McapCompression::zstd;  ///< chunk compression (default zstd)
  std::size_t chunk_bytes = 768 * 1024;  ///< a chunk is closed once its records exceed this, bytes
};

class McapWriter {
 public:
  /// Creates `file` and writes the magic and the Header. Throws InputError when it cannot be
  /// written.
  McapWriter(const std::filesystem::path& file, const McapWriterOptions& options = {});
  /// Closes the file if close() was not called (without checking the result: call close()).
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// A Schema record (`id` > 0, each once, before the channels that use it).
  void addSchema(std::uint16_t id, const std::string& name, const std::string& encoding,
                 const std::string& data);
  /// A Channel record; `metadata` is the MCAP Map as recorded (its uint32 byte length included;
  /// empty: an empty map).
  void addChannel(std::uint16_t id, std::uint16_t schema_id, const std::string& topic,
                  const std::string& message_encoding, const std::string& metadata = {});
  /// A Message record in the current chunk.
  void addMessage(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time_ns,
                  std::uint64_t publish_time_ns, const std::uint8_t* data, std::size_t size);
  /// A Metadata record (its content as recorded: name, then the map), outside chunks.
  void addMetadata(const std::string& content);
  /// Writes the last chunk, DataEnd, the summary, the Footer and the magic. Throws InputError on
  /// a write error.
  void close();

 private:
  void flushChunk();
  void put(const std::string& bytes);
  void putRecord(std::uint8_t op, const std::string& content);

  std::filesystem::path file_;
  McapWriterOptions options_;
  std::ofstream out_;
  std::uint64_t offset_ = 0;
  bool closed_ = false;
  std::vector<std::string> schemas_, channels_;  // their records, repeated in the summary
  std::vector<std::string> chunk_indexes_, metadata_indexes_;
  // The open chunk: its records, times and, per channel, (log_time, offset in the records).
  std::string chunk_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;
  // Statistics.
  std::uint64_t messages_ = 0, first_time_ = 0, last_time_ = 0;
  std::uint32_t chunks_ = 0;
  std::map<std::uint16_t, std::uint64_t> channel_messages_;
};

}  // namespace lidarcal::io
