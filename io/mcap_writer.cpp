// SPDX-License-Identifier: BSD-3-Clause
#include "io/mcap_writer.hpp"

#include <algorithm>

#include <zlib.h>
#include <zstd.h>

#include "common/errors.hpp"

namespace lidarcal::io {
namespace {

// MCAP spec: opcodes of the records written here.
enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F
};
const std::string kMagic("\x89MCAP0\r\n", 8);

/// Little-endian integer of `bytes` bytes (MCAP spec, "Serialization").
std::string le(std::uint64_t v, int bytes) {
  std::string s(static_cast<std::size_t>(bytes), '\0');
  for (int i = 0; i < bytes; ++i)
    s[static_cast<std::size_t>(i)] = static_cast<char>((v >> (8 * i)) & 0xff);
  return s;
}
/// String and Bytes: uint32 length, then the bytes.
std::string prefixed(const std::string& s) { return le(s.size(), 4) + s; }
std::string record(std::uint8_t op, const std::string& content) {
  return std::string(1, static_cast<char>(op)) + le(content.size(), 8) + content;
}
std::uint32_t crc(const std::string& bytes) {
  return static_cast<std::uint32_t>(
      crc32_z(0L, reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

}  // namespace

McapWriter::McapWriter(const std::filesystem::path& file, const McapWriterOptions& options)
    : file_(file), options_(options), out_(file, std::ios::binary | std::ios::trunc) {
  if (!out_)
    throw InputError(file.string(), "", "cannot be created",
                     "check that its directory exists and is writable");
  put(kMagic);
  putRecord(kHeader, prefixed(options_.profile) + prefixed(options_.library));
}

McapWriter::~McapWriter() {
  if (!closed_) {
    try {
      close();
    } catch (...) {  // the caller did not close(): the file is left to its atomic write to discard
    }
  }
}

void McapWriter::put(const std::string& bytes) {
  out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  offset_ += bytes.size();
}

void McapWriter::putRecord(std::uint8_t op, const std::string& content) {
  put(record(op, content));
}

void McapWriter::addSchema(std::uint16_t id, const std::string& name, const std::string& encoding,
                           const std::string& data) {
  const std::string r =
      record(kSchema, le(id, 2) + prefixed(name) + prefixed(encoding) + prefixed(data));
  schemas_.push_back(r);
  put(r);
}

void McapWriter::addChannel(std::uint16_t id, std::uint16_t schema_id, const std::string& topic,
                            const std::string& message_encoding, const std::string& metadata) {
  const std::string r =
      record(kChannel, le(id, 2) + le(schema_id, 2) + prefixed(topic) + prefixed(message_encoding) +
                           (metadata.empty() ? le(0, 4) : metadata));
  channels_.push_back(r);
  put(r);
}

void McapWriter::addMessage(std::uint16_t channel_id, std::uint32_t sequence,
                            std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                            const std::uint8_t* data, std::size_t size) {
  if (chunk_.empty()) chunk_start_ = chunk_end_ = log_time_ns;
  chunk_start_ = std::min(chunk_start_, log_time_ns);
  chunk_end_ = std::max(chunk_end_, log_time_ns);
  chunk_index_[channel_id].emplace_back(log_time_ns, chunk_.size());
  chunk_ += record(kMessage, le(channel_id, 2) + le(sequence, 4) + le(log_time_ns, 8) +
                                 le(publish_time_ns, 8) +
                                 std::string(reinterpret_cast<const char*>(data), size));
  first_time_ = messages_ == 0 ? log_time_ns : std::min(first_time_, log_time_ns);
  last_time_ = messages_ == 0 ? log_time_ns : std::max(last_time_, log_time_ns);
  ++messages_;
  ++channel_messages_[channel_id];
  if (chunk_.size() >= options_.chunk_bytes) flushChunk();
}

void McapWriter::addMetadata(const std::string& content) {
  // MetadataIndex: offset, length (of the whole record), name (the content's first string).
  const std::uint64_t at = offset_;
  const std::string r = record(kMetadata, content);
  put(r);
  std::uint32_t name_bytes = 0;
  for (int i = 3; i >= 0 && content.size() >= 4; --i)
    name_bytes =
        (name_bytes << 8) | static_cast<unsigned char>(content[static_cast<std::size_t>(i)]);
  const std::string name =
      content.size() >= 4 + std::size_t{name_bytes} ? content.substr(4, name_bytes) : std::string();
  metadata_indexes_.push_back(record(kMetadataIndex, le(at, 8) + le(r.size(), 8) + prefixed(name)));
}

/// The open chunk as a Chunk record, then one MessageIndex record per channel (MCAP spec, "Chunk",
/// "Message Index"), and its ChunkIndex for the summary.
void McapWriter::flushChunk() {
  if (chunk_.empty()) return;
  std::string packed = chunk_;
  std::string compression;
  if (options_.compression == McapCompression::zstd) {
    compression = "zstd";
    packed.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t n =
        ZSTD_compress(packed.data(), packed.size(), chunk_.data(), chunk_.size(), 3);
    if (ZSTD_isError(n))
      throw InputError(file_.string(), "chunk",
                       std::string("zstd failed: ") + ZSTD_getErrorName(n));
    packed.resize(n);
  }
  const std::uint64_t chunk_at = offset_;
  const std::string chunk = record(
      kChunk, le(chunk_start_, 8) + le(chunk_end_, 8) + le(chunk_.size(), 8) + le(crc(chunk_), 4) +
                  prefixed(compression) + le(packed.size(), 8) + packed);
  put(chunk);
  const std::uint64_t index_at = offset_;
  std::string offsets;
  for (const auto& [channel, entries] : chunk_index_) {
    std::string pairs;
    for (const auto& [time, at] : entries) pairs += le(time, 8) + le(at, 8);
    offsets += le(channel, 2) + le(offset_, 8);
    putRecord(kMessageIndex, le(channel, 2) + le(pairs.size(), 4) + pairs);
  }
  chunk_indexes_.push_back(record(
      kChunkIndex, le(chunk_start_, 8) + le(chunk_end_, 8) + le(chunk_at, 8) + le(chunk.size(), 8) +
                       le(offsets.size(), 4) + offsets + le(offset_ - index_at, 8) +
                       prefixed(compression) + le(packed.size(), 8) + le(chunk_.size(), 8)));
  ++chunks_;
  chunk_.clear();
  chunk_index_.clear();
}

void McapWriter::close() {
  if (closed_) return;
  closed_ = true;
  flushChunk();
  putRecord(kDataEnd, le(0, 4));  // data_section_crc 0: not computed (allowed by the spec)
  const std::uint64_t summary_start = offset_;
  std::string summary;
  struct Group {
    std::uint8_t op;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](std::uint8_t op, const std::vector<std::string>& records) {
    if (records.empty()) return;
    const std::uint64_t start = summary_start + summary.size();
    for (const auto& r : records) summary += r;
    groups.push_back({op, start, summary_start + summary.size() - start});
  };
  group(kSchema, schemas_);
  group(kChannel, channels_);
  std::string counts;
  for (const auto& [channel, n] : channel_messages_) counts += le(channel, 2) + le(n, 8);
  group(kStatistics,
        {record(kStatistics, le(messages_, 8) + le(schemas_.size(), 2) + le(channels_.size(), 4) +
                                 le(0, 4) + le(metadata_indexes_.size(), 4) + le(chunks_, 4) +
                                 le(first_time_, 8) + le(last_time_, 8) + le(counts.size(), 4) +
                                 counts)});
  group(kChunkIndex, chunk_indexes_);
  group(kMetadataIndex, metadata_indexes_);
  const std::uint64_t offsets_start = summary_start + summary.size();
  for (const auto& g : groups)
    summary += record(kSummaryOffset,
                      std::string(1, static_cast<char>(g.op)) + le(g.start, 8) + le(g.length, 8));
  // Footer: summary_start, summary_offset_start, then the CRC-32 of the summary up to and including
  // those two fields.
  const std::string footer_head = std::string(1, static_cast<char>(kFooter)) + le(8 + 8 + 4, 8) +
                                  le(summary_start, 8) + le(offsets_start, 8);
  put(summary);
  put(footer_head + le(crc(summary + footer_head), 4));
  put(kMagic);
  out_.flush();
  if (!out_)
    throw InputError(file_.string(), "", "could not be written completely (disk full?)",
                     "free some space and run again");
}

}  // namespace lidarcal::io
