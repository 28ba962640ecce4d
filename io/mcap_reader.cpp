// SPDX-License-Identifier: BSD-3-Clause
#include "io/mcap_reader.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <queue>
#include <tuple>

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include "common/errors.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;

// MCAP spec, "Magic": the file starts and ends with these 8 bytes.
constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
// MCAP spec, "Records": opcode (uint8), content length (uint64), content.
constexpr std::size_t kRecordHeadBytes = 9;
enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMetadata = 0x0C
};
// Message record: channel_id uint16, sequence uint32, log_time uint64, publish_time uint64, then
// the data.
constexpr std::size_t kMessageFixedBytes = 2 + 4 + 8 + 8;

const char* const kRemedy =
    "the file is damaged or cut short (recording interrupted): `mcap recover IN.mcap -o OUT.mcap` "
    "(the mcap CLI) "
    "rescues what it can; or record it again";

std::string opcodeName(std::uint8_t op) {
  static const char* const kNames[] = {
      "?",        "Header",        "Footer",        "Schema",     "Channel",         "Message",
      "Chunk",    "MessageIndex",  "ChunkIndex",    "Attachment", "AttachmentIndex", "Statistics",
      "Metadata", "MetadataIndex", "SummaryOffset", "DataEnd"};
  if (op >= 1 && op <= 0x0f) return kNames[op];
  char text[24];
  std::snprintf(text, sizeof text, "opcode 0x%02x", op);
  return text;
}

/// Where a record lies, for messages.
struct Place {
  const std::string& file;
  std::string where;
};

[[noreturn]] void corrupt(const Place& place, const std::string& problem) {
  throw InputError(place.file, place.where, problem, kRemedy);
}

/// The little-endian fields of one record's content (MCAP spec, "Serialization"), bounds-checked.
class Fields {
 public:
  Fields(const std::uint8_t* data, std::uint64_t size, const Place& place)
      : p_(data), n_(size), place_(place) {}
  std::uint64_t left() const { return n_ - pos_; }
  const std::uint8_t* take(std::uint64_t n) {
    if (n > left())
      corrupt(place_, "a field of " + std::to_string(n) + " bytes at byte " + std::to_string(pos_) +
                          " of the record runs past its end (" + std::to_string(n_) + " bytes)");
    const std::uint8_t* at = p_ + pos_;
    pos_ += n;
    return at;
  }
  std::uint64_t uint(std::size_t bytes) {
    const std::uint8_t* at = take(bytes);
    std::uint64_t v = 0;
    for (std::size_t i = bytes; i-- > 0;) v = (v << 8) | at[i];
    return v;
  }
  std::uint16_t u16() { return static_cast<std::uint16_t>(uint(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(uint(4)); }
  std::uint64_t u64() { return uint(8); }
  /// String, Bytes and Map: a uint32 byte length, then that many bytes.
  std::string str() {
    const std::uint32_t n = u32();
    const std::uint8_t* at = take(n);
    return std::string(reinterpret_cast<const char*>(at), n);
  }
  void skipPrefixed() { take(u32()); }

 private:
  const std::uint8_t* p_;
  std::uint64_t n_;
  std::uint64_t pos_ = 0;
  const Place& place_;
};

/// One record inside a buffer (a chunk's records).
struct Record {
  std::uint8_t op = 0;
  const std::uint8_t* content = nullptr;
  std::uint64_t length = 0;
};

/// The record at `pos` of `buf` (advancing `pos`); false at the end.
bool nextRecord(const std::vector<std::uint8_t>& buf, std::uint64_t& pos, Record& r,
                const Place& chunk) {
  if (pos == buf.size()) return false;
  const Place here{chunk.file,
                   chunk.where + ", record at byte " + std::to_string(pos) + " of its records"};
  Fields f(buf.data() + pos, buf.size() - pos, here);
  r.op = static_cast<std::uint8_t>(f.uint(1));
  r.length = f.u64();
  r.content = f.take(r.length);
  pos += kRecordHeadBytes + r.length;
  return true;
}

/// A chunk's records, decompressed (MCAP spec, "Chunk": compression "", "zstd" or "lz4").
struct ChunkHead {
  std::uint64_t start_time = 0, end_time = 0, uncompressed_size = 0;
  std::uint32_t crc = 0;
  std::string compression;
  const std::uint8_t* records = nullptr;
  std::uint64_t records_size = 0;
};

ChunkHead parseChunkHead(const std::vector<std::uint8_t>& content, const Place& place) {
  Fields f(content.data(), content.size(), place);
  ChunkHead h;
  h.start_time = f.u64();
  h.end_time = f.u64();
  h.uncompressed_size = f.u64();
  h.crc = f.u32();
  h.compression = f.str();
  h.records_size = f.u64();
  h.records = f.take(h.records_size);
  return h;
}

void decompressZstd(const ChunkHead& h, std::vector<std::uint8_t>& out, const Place& place) {
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), h.records, h.records_size);
  if (ZSTD_isError(n))
    corrupt(place, std::string("zstd cannot decompress the records (") + ZSTD_getErrorName(n) +
                       "; more data than uncompressed_size also gives this)");
  if (n != out.size())
    corrupt(place, "the records decompress to " + std::to_string(n) +
                       " bytes, uncompressed_size says " + std::to_string(out.size()));
}

// LZ4 frame format (not raw LZ4 blocks), as the MCAP spec's "lz4" compression names it.
void decompressLz4(const ChunkHead& h, std::vector<std::uint8_t>& out, const Place& place) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
    corrupt(place, "lz4: out of memory");
  std::size_t in_done = 0, out_done = 0, hint = 1;
  while (in_done < h.records_size && hint != 0) {
    std::size_t out_n = out.size() - out_done,
                in_n = static_cast<std::size_t>(h.records_size) - in_done;
    hint = LZ4F_decompress(ctx, out.data() + out_done, &out_n, h.records + in_done, &in_n, nullptr);
    if (LZ4F_isError(hint)) break;
    // output full with input left: more data than uncompressed_size
    if (in_n == 0 && out_n == 0) break;
    in_done += in_n;
    out_done += out_n;
  }
  LZ4F_freeDecompressionContext(ctx);
  if (LZ4F_isError(hint))
    corrupt(place,
            std::string("lz4 cannot decompress the records (") + LZ4F_getErrorName(hint) + ")");
  if (hint != 0 || in_done != h.records_size || out_done != out.size())
    corrupt(place, "the lz4 records do not decompress to uncompressed_size (" +
                       std::to_string(out.size()) +
                       " bytes): the chunk is cut short or its size is wrong");
}

/// The chunk's records, uncompressed, in `out`. Checks uncompressed_size (capped) and the CRC when
/// given.
void unpackChunk(const ChunkHead& h, std::vector<std::uint8_t>& out, const Place& place) {
  if (h.compression != "" && h.compression != "zstd" && h.compression != "lz4")
    corrupt(place,
            "unknown compression '" + h.compression + "' (this reader knows none, zstd and lz4)");
  const std::uint64_t cap =
      std::min<std::uint64_t>(kMaxChunkBytes, h.records_size * 1024 + (1u << 20));
  if (h.uncompressed_size > cap || (h.compression.empty() && h.uncompressed_size != h.records_size))
    corrupt(place, "uncompressed_size " + std::to_string(h.uncompressed_size) +
                       " does not fit its " + std::to_string(h.records_size) + " bytes of " +
                       (h.compression.empty() ? "uncompressed" : h.compression) + " records");
  out.resize(static_cast<std::size_t>(h.uncompressed_size));
  if (h.compression.empty())
    std::copy(h.records, h.records + h.records_size, out.begin());
  else if (h.compression == "zstd")
    decompressZstd(h, out, place);
  else
    decompressLz4(h, out, place);
  // MCAP spec: uncompressed_crc is the CRC-32 of the uncompressed records; 0 means not computed.
  if (h.crc != 0 && crc32_z(0L, out.data(), out.size()) != h.crc)
    corrupt(place, "the records fail their CRC-32 check");
}

/// A chunk, or a message outside chunks, and the messages in it.
struct Source {
  std::uint64_t offset = 0;  ///< byte offset of the record
  std::uint64_t length = 0;  ///< content length
  bool chunk = false;
  std::uint64_t min_time = ~std::uint64_t{0};  ///< earliest log_time of its messages
  std::vector<std::uint16_t> channels;         ///< channel ids of its messages, sorted, unique
};

}  // namespace

struct McapReader::Impl {
  fs::path path;
  std::string name;
  std::ifstream in;
  std::uint64_t size = 0;
  std::vector<Source> sources;  // in file order
  struct SchemaRecord {
    std::string name, encoding, data;
  };
  std::map<std::uint16_t, SchemaRecord> schemas;    // id -> schema
  std::vector<std::string> metadata;                // contents of the Metadata records
  std::map<std::uint16_t, std::size_t> channel_at;  // id -> index in channels

  /// `n` bytes at `offset` (checked against the file size by the caller).
  void read(std::uint64_t offset, std::uint64_t n, std::vector<std::uint8_t>& buf,
            const Place& place) {
    buf.resize(static_cast<std::size_t>(n));
    in.clear();
    in.seekg(static_cast<std::streamoff>(offset));
    in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n));
    if (static_cast<std::uint64_t>(in.gcount()) != n)
      corrupt(place, "cannot be read (I/O error or the file shrank)");
  }
};

namespace {

using Impl = McapReader::Impl;

/// Schema and Channel records (MCAP spec, "Schema", "Channel"): the first definition of an id
/// counts (the summary section repeats them).
void define(Impl& im, std::vector<McapChannel>& channels, const Record& r, const Place& place) {
  Fields f(r.content, r.length, place);
  if (r.op == kSchema) {
    const std::uint16_t id = f.u16();
    Impl::SchemaRecord schema;
    schema.name = f.str();
    schema.encoding = f.str();
    schema.data = f.str();
    im.schemas.emplace(id, std::move(schema));
    return;
  }
  McapChannel c;
  c.id = f.u16();
  const std::uint16_t schema_id = f.u16();
  c.topic = f.str();
  c.message_encoding = f.str();
  const std::uint32_t metadata_bytes = f.u32();
  const std::uint8_t* metadata = f.take(metadata_bytes);
  c.metadata.assign(reinterpret_cast<const char*>(metadata) - 4, metadata_bytes + 4);
  if (schema_id != 0 && !im.schemas.count(schema_id))
    corrupt(place, "channel " + std::to_string(c.id) + " refers to schema " +
                       std::to_string(schema_id) + ", which no Schema record before it defines");
  if (schema_id != 0) {
    const Impl::SchemaRecord& schema = im.schemas.at(schema_id);
    c.schema_id = schema_id;
    c.schema_name = schema.name;
    c.schema_encoding = schema.encoding;
    c.schema_data = schema.data;
  }
  if (im.channel_at.emplace(c.id, channels.size()).second) channels.push_back(std::move(c));
}

/// A Message record's channel and log_time; counts it on its channel and in `source`.
void noteMessage(Impl& im, std::vector<McapChannel>& channels, const Record& r, Source& source,
                 const Place& place) {
  Fields f(r.content, r.length, place);
  const std::uint16_t channel = f.u16();
  f.u32();  // sequence
  const std::uint64_t log_time = f.u64();
  f.u64();  // publish_time
  const auto it = im.channel_at.find(channel);
  if (it == im.channel_at.end())
    corrupt(place, "a message on channel " + std::to_string(channel) +
                       ", which no Channel record before it defines");
  ++channels[it->second].messages;
  source.min_time = std::min(source.min_time, log_time);
  if (!std::binary_search(source.channels.begin(), source.channels.end(), channel))
    source.channels.insert(
        std::upper_bound(source.channels.begin(), source.channels.end(), channel), channel);
}

void indexChunk(Impl& im, std::vector<McapChannel>& channels, Source& source, const Place& place) {
  std::vector<std::uint8_t> content, records;
  im.read(source.offset + kRecordHeadBytes, source.length, content, place);
  unpackChunk(parseChunkHead(content, place), records, place);
  std::uint64_t pos = 0;
  Record r;
  while (nextRecord(records, pos, r, place)) {
    const Place inner{place.file, place.where + ", its " + opcodeName(r.op) + " record"};
    if (r.op == kSchema || r.op == kChannel)
      define(im, channels, r, inner);
    else if (r.op == kMessage)
      noteMessage(im, channels, r, source, inner);
  }
}

/// The opcode and content length of the record at `pos`, checked against the file's end.
Record recordHead(Impl& im, std::uint64_t pos) {
  const Place place{im.name, "byte " + std::to_string(pos)};
  if (im.size - pos < kRecordHeadBytes)
    corrupt(place, "the file ends inside the data section, without a Footer record");
  std::vector<std::uint8_t> head;
  im.read(pos, kRecordHeadBytes, head, place);
  Record r;
  r.op = head[0];
  Fields f(head.data() + 1, 8, place);
  r.length = f.u64();
  if (r.length > im.size - pos - kRecordHeadBytes)
    corrupt({im.name, "record at byte " + std::to_string(pos) + " (" + opcodeName(r.op) + ")"},
            "its length " + std::to_string(r.length) + " runs past the end of the file (" +
                std::to_string(im.size) +
                " bytes): the file is cut short, or the length is damaged");
  return r;
}

void checkMagic(Impl& im, std::uint64_t pos, const char* which) {
  const Place place{im.name, std::string(which) + " magic at byte " + std::to_string(pos)};
  if (im.size < pos + sizeof kMagic) corrupt(place, "missing: the file ends first");
  std::vector<std::uint8_t> magic;
  im.read(pos, sizeof kMagic, magic, place);
  if (!std::equal(magic.begin(), magic.end(), kMagic))
    throw InputError(im.name, place.where,
                     "not the MCAP magic \\x89MCAP0\\r\\n: not an MCAP file, or a damaged one",
                     kRemedy);
}

/// Reads the data section record by record up to the Footer (MCAP spec, "File Structure").
void indexFile(Impl& im, std::vector<McapChannel>& channels) {
  checkMagic(im, 0, "opening");
  std::uint64_t pos = sizeof kMagic;
  for (bool first = true;; first = false) {
    Record r = recordHead(im, pos);
    const Place place{im.name,
                      "record at byte " + std::to_string(pos) + " (" + opcodeName(r.op) + ")"};
    if (first && r.op != kHeader) corrupt(place, "the first record must be a Header");
    Source s;
    s.offset = pos;
    s.length = r.length;
    std::vector<std::uint8_t> content;
    if (r.op == kFooter) return checkMagic(im, pos + kRecordHeadBytes + r.length, "closing");
    if (r.op == kSchema || r.op == kChannel || r.op == kMessage) {
      im.read(pos + kRecordHeadBytes,
              std::min<std::uint64_t>(r.length, r.op == kMessage ? kMessageFixedBytes : r.length),
              content, place);
      r.content = content.data();
      if (r.op == kMessage && r.length < kMessageFixedBytes)
        corrupt(place, "shorter than a Message's fixed fields");
      if (r.op == kMessage) r.length = kMessageFixedBytes;
    }
    if (r.op == kSchema || r.op == kChannel)
      define(im, channels, r, place);
    else if (r.op == kMessage)
      noteMessage(im, channels, r, s, place);
    else if (r.op == kMetadata) {
      im.read(pos + kRecordHeadBytes, r.length, content, place);
      im.metadata.emplace_back(content.begin(), content.end());
    } else if (r.op == kChunk) {
      s.chunk = true;
      indexChunk(im, channels, s, place);
    }
    if ((r.op == kMessage || r.op == kChunk) && !s.channels.empty())
      im.sources.push_back(std::move(s));
    pos += kRecordHeadBytes + s.length;  // other records (index, summary, unknown opcodes) skipped
  }
}

/// The messages of one source on the wanted channels, sorted by log_time (stable).
struct Loaded {
  std::vector<std::uint8_t> content, records;
  struct Entry {
    std::uint64_t time;
    const McapChannel* channel;
    const std::uint8_t* data;
    std::size_t size;
    std::uint32_t sequence;
    std::uint64_t publish_time;
  };
  std::vector<Entry> entries;
  std::size_t left = 0;
};

void addEntry(const Record& r, const std::vector<McapChannel>& channels, const Impl& im,
              const std::vector<bool>& wanted, Loaded& out, const Place& place) {
  Fields f(r.content, r.length, place);
  const std::uint16_t channel = f.u16();
  const std::uint32_t sequence = f.u32();
  const std::uint64_t time = f.u64();
  const std::uint64_t publish_time = f.u64();
  if (!wanted[channel]) return;
  const std::uint64_t size = f.left();
  out.entries.push_back({time, &channels[im.channel_at.at(channel)], f.take(size),
                         static_cast<std::size_t>(size), sequence, publish_time});
}

void load(Impl& im, const Source& s, const std::vector<McapChannel>& channels,
          const std::vector<bool>& wanted, Loaded& out) {
  const Place place{im.name, "record at byte " + std::to_string(s.offset) +
                                 (s.chunk ? " (Chunk)" : " (Message)")};
  im.read(s.offset + kRecordHeadBytes, s.length, out.content, place);
  if (!s.chunk) {
    addEntry({kMessage, out.content.data(), s.length}, channels, im, wanted, out, place);
  } else {
    unpackChunk(parseChunkHead(out.content, place), out.records, place);
    out.content = {};
    std::uint64_t pos = 0;
    Record r;
    while (nextRecord(out.records, pos, r, place))
      if (r.op == kMessage) addEntry(r, channels, im, wanted, out, place);
  }
  std::stable_sort(out.entries.begin(), out.entries.end(),
                   [](const auto& a, const auto& b) { return a.time < b.time; });
  out.left = out.entries.size();
}

}  // namespace

McapReader::McapReader(const fs::path& file) : impl_(std::make_unique<Impl>()) {
  impl_->path = file;
  impl_->name = file.string();
  std::error_code ec;
  if (!fs::exists(file, ec))
    throw InputError(impl_->name, "", "file does not exist", "check the path");
  impl_->in.open(file, std::ios::binary);
  const auto size = fs::file_size(file, ec);
  if (!impl_->in || ec)
    throw InputError(impl_->name, "", "cannot be opened for reading", "check its permissions");
  impl_->size = size;
  indexFile(*impl_, channels_);
}

McapReader::~McapReader() = default;

const std::vector<std::string>& McapReader::metadataRecords() const { return impl_->metadata; }

bool McapReader::forEachMessage(const std::set<std::string>& topics,
                                const McapMessageCallback& on_message) const {
  std::vector<bool> wanted(65536, false);
  for (const auto& c : channels_) wanted[c.id] = topics.count(c.topic) > 0;
  // Sources holding a wanted channel, by earliest log_time (ties in file order).
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < impl_->sources.size(); ++k) {
    const auto& ch = impl_->sources[k].channels;
    if (std::any_of(ch.begin(), ch.end(), [&](std::uint16_t id) { return wanted[id]; }))
      order.push_back(k);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return impl_->sources[a].min_time < impl_->sources[b].min_time;
  });
  // k-way merge: a source is loaded once the next message due is not earlier than its first.
  // log_time, source (file order), entry
  using Key = std::tuple<std::uint64_t, std::size_t, std::size_t>;
  std::priority_queue<Key, std::vector<Key>, std::greater<Key>> due;
  std::map<std::size_t, Loaded> open;
  std::size_t next = 0;
  for (;;) {
    while (next < order.size() &&
           (due.empty() || impl_->sources[order[next]].min_time <= std::get<0>(due.top()))) {
      const std::size_t k = order[next++];
      Loaded& l = open[k];
      load(*impl_, impl_->sources[k], channels_, wanted, l);
      for (std::size_t i = 0; i < l.entries.size(); ++i) due.emplace(l.entries[i].time, k, i);
      if (l.left == 0) open.erase(k);
    }
    if (due.empty()) return true;
    const auto [time, k, i] = due.top();
    due.pop();
    Loaded& l = open.at(k);
    const auto& e = l.entries[i];
    if (!on_message({e.channel, time, e.publish_time, e.sequence, e.data, e.size})) return false;
    if (--l.left == 0) open.erase(k);  // memory back as soon as a source is done
  }
}

}  // namespace lidarcal::io
