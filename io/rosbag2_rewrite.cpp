// SPDX-License-Identifier: BSD-3-Clause
#include "io/rosbag2_rewrite.hpp"

#include <fstream>
#include <memory>
#include <set>
#include <sstream>

#include <sqlite3.h>

#include "common/errors.hpp"
#include "io/bag_scans.hpp"
#include "io/mcap_reader.hpp"
#include "io/mcap_writer.hpp"
#include "io/ros2_msgs.hpp"
#include "io/rosbag2_storage.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;

/// Decodes one LaserScan of a chosen topic, hands its ranges to the callback and patches them into
/// `bytes`.
class ScanPatcher {
 public:
  ScanPatcher(const fs::path& file, const TopicRangesCallback& on_scan, BagRewriteReport& report)
      : file_(file.string()), on_scan_(on_scan), report_(report) {}

  void patch(const std::string& topic, std::vector<std::uint8_t>& bytes) {
    try {
      decodeLaserScan(bytes.data(), bytes.size(), msg_);
    } catch (const InputError& e) {
      throw InputError(
          file_, "topic " + topic + ", message " + std::to_string(report_.scans) + ", " + e.item(),
          std::string("is not a valid CDR ") + kRos2Flavour.scan_type + ": " + e.problem(),
          "the bag is damaged, or the topic holds another type than it declares");
    }
    fillRawScan(msg_.view(), RosbagConfig{}, scan_);
    scan_.source_index = report_.scans++;
    on_scan_(topic, msg_.ranges, scan_);
    patchLaserScanRanges(msg_, bytes.data(), bytes.size());
  }

 private:
  std::string file_;
  const TopicRangesCallback& on_scan_;
  BagRewriteReport& report_;
  Ros2LaserScan msg_;  // reused: its vectors keep their capacity
  RawScan scan_;
};

using Topics = std::set<std::string>;

void rewriteMcap(const fs::path& in, const fs::path& out, const Topics& chosen,
                 ScanPatcher& patcher, BagRewriteReport& report) {
  const McapReader reader(in);
  McapWriter writer(out);
  std::set<std::uint16_t> schemas;
  std::set<std::string> topics;
  for (const McapChannel& c : reader.channels()) {
    if (c.schema_id != 0 && schemas.insert(c.schema_id).second)
      writer.addSchema(c.schema_id, c.schema_name, c.schema_encoding, c.schema_data);
    writer.addChannel(c.id, c.schema_id, c.topic, c.message_encoding, c.metadata);
    topics.insert(c.topic);
    ++report.connections;
  }
  for (const std::string& m : reader.metadataRecords()) writer.addMetadata(m);
  std::vector<std::uint8_t> bytes;
  reader.forEachMessage(topics, [&](const McapMessage& m) {
    const std::uint8_t* data = m.data;
    if (chosen.count(m.channel->topic) > 0) {
      bytes.assign(m.data, m.data + m.size);
      patcher.patch(m.channel->topic, bytes);
      data = bytes.data();
    }
    writer.addMessage(m.channel->id, m.sequence, m.log_time_ns, m.publish_time_ns, data, m.size);
    ++report.messages;
    return true;
  });
  writer.close();
}

struct Db3 {
  sqlite3* db = nullptr;
  std::string name;
  Db3(const fs::path& file, int flags) : name(file.string()) {
    if (sqlite3_open_v2(name.c_str(), &db, flags, nullptr) != SQLITE_OK)
      fail("", "cannot be opened");
  }
  ~Db3() { sqlite3_close(db); }
  [[noreturn]] void fail(const std::string& item, const std::string& problem) const {
    throw InputError(name, item,
                     problem + " (sqlite: " + (db ? sqlite3_errmsg(db) : "out of memory") + ")",
                     "`ros2 bag info BAG` shows whether ROS 2 can read it");
  }
};
struct Statement {
  sqlite3_stmt* s = nullptr;
  Statement(const Db3& db, const std::string& sql) {
    if (sqlite3_prepare_v2(db.db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK)
      db.fail(sql, "cannot be run");
  }
  ~Statement() { sqlite3_finalize(s); }
};

void rewriteDb3(const fs::path& in, const fs::path& out, const Topics& chosen, ScanPatcher& patcher,
                BagRewriteReport& report) {
  std::error_code ec;
  fs::copy_file(in, out, fs::copy_options::overwrite_existing, ec);
  if (ec)
    throw InputError(out.string(), "", "cannot be written: " + ec.message(),
                     "check the output directory");
  const Db3 src(in, SQLITE_OPEN_READONLY), dst(out, SQLITE_OPEN_READWRITE);
  // One query over every chosen topic: the messages reach the callback in time order, as from an
  // MCAP.
  std::string marks;
  for (std::size_t i = 0; i < chosen.size(); ++i) marks += i == 0 ? "?" : ", ?";
  Statement rows(src,
                 "SELECT m.id, m.data, t.name FROM messages m JOIN topics t ON m.topic_id = t.id "
                 "WHERE t.name IN (" +
                     marks + ") ORDER BY m.timestamp, m.id");
  int at = 0;
  for (const std::string& t : chosen)
    sqlite3_bind_text(rows.s, ++at, t.c_str(), -1, SQLITE_TRANSIENT);
  if (sqlite3_exec(dst.db, "BEGIN", nullptr, nullptr, nullptr) != SQLITE_OK)
    dst.fail("BEGIN", "cannot be run");
  Statement update(dst, "UPDATE messages SET data = ? WHERE id = ?");
  std::vector<std::uint8_t> bytes;
  int rc;
  while ((rc = sqlite3_step(rows.s)) == SQLITE_ROW) {
    const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(rows.s, 1));
    bytes.assign(data, data + sqlite3_column_bytes(rows.s, 1));
    patcher.patch(reinterpret_cast<const char*>(sqlite3_column_text(rows.s, 2)), bytes);
    sqlite3_bind_blob(update.s, 1, bytes.data(), static_cast<int>(bytes.size()), SQLITE_STATIC);
    sqlite3_bind_int64(update.s, 2, sqlite3_column_int64(rows.s, 0));
    if (sqlite3_step(update.s) != SQLITE_DONE) dst.fail("table messages", "cannot be updated");
    sqlite3_reset(update.s);
  }
  if (rc != SQLITE_DONE) src.fail("table messages", "cannot be read");
  if (sqlite3_exec(dst.db, "COMMIT", nullptr, nullptr, nullptr) != SQLITE_OK)
    dst.fail("COMMIT", "cannot be run");
  Statement count(src, "SELECT COUNT(*) FROM messages");
  if (sqlite3_step(count.s) == SQLITE_ROW)
    report.messages += static_cast<std::size_t>(sqlite3_column_int64(count.s, 0));
  Statement topics(src, "SELECT COUNT(*) FROM topics");
  if (sqlite3_step(topics.s) == SQLITE_ROW)
    report.connections += static_cast<std::size_t>(sqlite3_column_int64(topics.s, 0));
}

bool isMcap(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char head[8] = {};
  in.read(head, sizeof head);
  return in.gcount() == 8 && std::string(head, 8) == std::string("\x89MCAP0\r\n", 8);
}

void rewriteFile(const fs::path& in, const fs::path& out, const Topics& chosen,
                 ScanPatcher& patcher, BagRewriteReport& report) {
  if (isMcap(in))
    rewriteMcap(in, out, chosen, patcher, report);
  else
    rewriteDb3(in, out, chosen, patcher, report);
}

}  // namespace

BagRewriteReport rewriteRosbag2(const fs::path& in, const fs::path& out, const std::string& wanted,
                                const RangesCallback& on_scan) {
  return rewriteRosbag2Topics(
      in, out, {wanted}, [&](const std::string&, std::vector<float>& ranges, const RawScan& scan) {
        on_scan(ranges, scan);
      });
}

BagRewriteReport rewriteRosbag2Topics(const fs::path& in, const fs::path& out,
                                      const std::vector<std::string>& wanted,
                                      const TopicRangesCallback& on_scan) {
  BagRewriteReport report;
  // reads and checks the whole bag first
  const std::vector<BagTopic> bag_topics = Rosbag2(in).bagTopics();
  Topics chosen;
  for (const std::string& w : wanted) {
    const std::string topic = chooseScanTopic(in, bag_topics, w, kRos2Flavour);
    if (report.topic.empty()) report.topic = topic;
    chosen.insert(topic);
  }
  ScanPatcher patcher(in, on_scan, report);
  std::error_code ec;
  if (!fs::is_directory(in, ec)) {
    rewriteFile(in, out, chosen, patcher, report);
    return report;
  }
  std::ifstream yaml(in / "metadata.yaml", std::ios::binary);
  std::stringstream text;
  text << yaml.rdbuf();
  const Rosbag2Metadata meta = parseRosbag2Metadata(text.str(), (in / "metadata.yaml").string());
  fs::copy_file(in / "metadata.yaml", out / "metadata.yaml", ec);
  if (ec)
    throw InputError((out / "metadata.yaml").string(), "", "cannot be written: " + ec.message(),
                     "check the output directory");
  for (const std::string& rel : meta.relative_file_paths) {
    if (fs::path(rel).has_parent_path())
      throw InputError((in / "metadata.yaml").string(), "relative_file_paths",
                       "lists " + rel + ", outside the bag directory",
                       "`ros2 bag reindex DIR` rewrites metadata.yaml with the files' names");
    rewriteFile(in / rel, out / rel, chosen, patcher, report);
  }
  return report;
}

}  // namespace lidarcal::io
