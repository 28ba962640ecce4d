// SPDX-License-Identifier: BSD-3-Clause
#include "io/rosbag2_storage.hpp"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include <sqlite3.h>

#include "common/errors.hpp"
#include "io/mcap_reader.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;

const char* const kDb3Remedy =
    "the file is not a rosbag2 SQLite bag or it is damaged; `ros2 bag info BAG` shows whether ROS "
    "2 can read it";
const char* const kReindexRemedy =
    "`ros2 bag reindex DIR` rewrites metadata.yaml from the storage files";

/// An .mcap file of a ROS 2 bag.
class McapFile : public Rosbag2File {
 public:
  explicit McapFile(const fs::path& file) : reader_(file) {}
  std::vector<Rosbag2Topic> topics() const override {
    std::vector<Rosbag2Topic> out;
    for (const McapChannel& c : reader_.channels())
      out.push_back({{c.topic, c.schema_name, c.messages}, c.message_encoding});
    return out;
  }
  bool forEach(const std::set<std::string>& topics,
               const Rosbag2MessageCallback& on_message) const override {
    return reader_.forEachMessage(topics, [&](const McapMessage& m) {
      return on_message(
          {&m.channel->topic, static_cast<std::int64_t>(m.log_time_ns), m.data, m.size});
    });
  }

 private:
  McapReader reader_;
};

/// A prepared SQLite statement, finalised on scope exit.
struct Statement {
  sqlite3_stmt* s = nullptr;
  ~Statement() { sqlite3_finalize(s); }
};

/// A .db3 file (SQLite) of a ROS 2 bag, opened read-only.
class Db3File : public Rosbag2File {
 public:
  explicit Db3File(const fs::path& file) : name_(file.string()) {
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
      throw InputError(name_, "", "file does not exist", "check the path");
    sqlite3* db = nullptr;
    const int rc = sqlite3_open_v2(name_.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
    // closed on every path, also when the constructor throws (sqlite3_open_v2 may allocate on
    // failure)
    db_.reset(db);
    if (rc != SQLITE_OK) fail("", "cannot be opened");
    readTopics();
  }

  std::vector<Rosbag2Topic> topics() const override { return topics_; }

  bool forEach(const std::set<std::string>& topics,
               const Rosbag2MessageCallback& on_message) const override {
    std::string ids;
    for (const auto& [id, name] : names_)
      if (topics.count(name)) ids += (ids.empty() ? "" : ",") + std::to_string(id);
    if (ids.empty()) return true;
    Statement st;
    prepare(st,
            "SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN (" + ids +
                ") ORDER BY timestamp, id",
            "messages");
    int rc;
    while ((rc = sqlite3_step(st.s)) == SQLITE_ROW) {
      const auto it = names_.find(sqlite3_column_int64(st.s, 0));
      if (it == names_.end()) continue;
      const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(st.s, 2));
      const auto size = static_cast<std::size_t>(sqlite3_column_bytes(st.s, 2));
      if (!on_message({&it->second, sqlite3_column_int64(st.s, 1), data, size})) return false;
    }
    if (rc != SQLITE_DONE) fail("table messages", "cannot be read");
    return true;
  }

 private:
  [[noreturn]] void fail(const std::string& item, const std::string& problem) const {
    throw InputError(
        name_, item,
        problem + " (sqlite: " + (db_ ? sqlite3_errmsg(db_.get()) : "out of memory") + ")",
        kDb3Remedy);
  }
  void prepare(Statement& st, const std::string& sql, const std::string& table) const {
    if (sqlite3_prepare_v2(db_.get(), sql.c_str(), -1, &st.s, nullptr) != SQLITE_OK)
      fail("table " + table, "cannot be read");
  }
  /// topics(id, name, type, serialization_format) and the message count of each.
  void readTopics() {
    Statement st;
    prepare(st, "SELECT id, name, type, serialization_format FROM topics ORDER BY id", "topics");
    std::map<std::int64_t, std::size_t> at;
    int rc;
    while ((rc = sqlite3_step(st.s)) == SQLITE_ROW) {
      auto text = [&](int col) {
        const unsigned char* t = sqlite3_column_text(st.s, col);
        return t ? std::string(reinterpret_cast<const char*>(t)) : std::string();
      };
      const std::int64_t id = sqlite3_column_int64(st.s, 0);
      if (!names_.emplace(id, text(1)).second) continue;
      at[id] = topics_.size();
      topics_.push_back({{text(1), text(2), 0}, text(3)});
    }
    if (rc != SQLITE_DONE) fail("table topics", "cannot be read");
    Statement counts;
    prepare(counts, "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id", "messages");
    while ((rc = sqlite3_step(counts.s)) == SQLITE_ROW)
      if (const auto it = at.find(sqlite3_column_int64(counts.s, 0)); it != at.end())
        topics_[it->second].topic.messages =
            static_cast<std::size_t>(sqlite3_column_int64(counts.s, 1));
    if (rc != SQLITE_DONE) fail("table messages", "cannot be read");
  }

  struct Close {
    void operator()(sqlite3* db) const { sqlite3_close(db); }
  };
  std::string name_;
  std::unique_ptr<sqlite3, Close> db_;
  std::vector<Rosbag2Topic> topics_;
  std::map<std::int64_t, std::string> names_;  // topic id -> name
};

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") + 1 - a);
}

std::string unquote(std::string s) {
  s = trim(s);
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front())
    s = s.substr(1, s.size() - 2);
  return s;
}

/// `[a, b]` (flow style) as a list.
std::vector<std::string> flowList(const std::string& value) {
  std::vector<std::string> out;
  std::stringstream items(value.substr(
      1, value.find(']') == std::string::npos ? std::string::npos : value.find(']') - 1));
  std::string item;
  while (std::getline(items, item, ','))
    if (!unquote(item).empty()) out.push_back(unquote(item));
  return out;
}

std::unique_ptr<Rosbag2File> openFile(const fs::path& file, const std::string& storage) {
  if (storage == "mcap") return std::make_unique<McapFile>(file);
  return std::make_unique<Db3File>(file);
}

/// The storage of a single file, from its first bytes.
std::string storageOf(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::error_code ec;
  if (!fs::exists(file, ec))
    throw InputError(file.string(), "", "file does not exist", "check the path");
  if (!in)
    throw InputError(file.string(), "", "cannot be opened for reading", "check its permissions");
  char head[16] = {};
  in.read(head, sizeof head);
  const std::string magic(head, static_cast<std::size_t>(in.gcount()));
  if (magic.rfind("\x89MCAP0\r\n", 0) == 0) return "mcap";
  if (magic == std::string("SQLite format 3\0", 16)) return "sqlite3";
  throw InputError(file.string(), "", "is neither an MCAP file nor a rosbag2 SQLite (.db3) file",
                   "pass a ROS 2 bag: its directory (with metadata.yaml), an .mcap or a .db3 file");
}

/// The storage files a rosbag2 directory's metadata.yaml lists, checked to exist.
std::vector<fs::path> listedFiles(const fs::path& dir, Rosbag2Metadata& meta) {
  const fs::path yaml = dir / "metadata.yaml";
  std::error_code ec;
  if (!fs::is_regular_file(yaml, ec))
    throw InputError(dir.string(), "metadata.yaml",
                     "missing: not a rosbag2 directory, or its recording was interrupted",
                     std::string(kReindexRemedy) + "; or pass one of its .mcap/.db3 files");
  std::ifstream in(yaml);
  std::stringstream text;
  text << in.rdbuf();
  meta = parseRosbag2Metadata(text.str(), yaml.string());
  if (!meta.compression_mode.empty() && meta.compression_mode != "NONE")
    throw InputError(
        yaml.string(), "compression_mode",
        "the bag is compressed by rosbag2 (" + meta.compression_mode + ", " +
            meta.compression_format + "): not supported",
        "`ros2 bag convert` writes an uncompressed copy (MCAP chunk compression is supported)");
  std::vector<fs::path> files;
  for (const std::string& rel : meta.relative_file_paths) {
    // Older rosbag2 versions wrote the paths relative to the bag's parent directory.
    fs::path p = dir / rel;
    if (!fs::exists(p, ec) && fs::exists(dir.parent_path() / rel, ec)) p = dir.parent_path() / rel;
    if (!fs::is_regular_file(p, ec))
      throw InputError(yaml.string(), "relative_file_paths",
                       "lists " + rel + ", which is not in " + dir.string(),
                       "copy the whole bag directory, or " + std::string(kReindexRemedy));
    files.push_back(p);
  }
  return files;
}

}  // namespace

Rosbag2Metadata parseRosbag2Metadata(const std::string& text, const std::string& file) {
  Rosbag2Metadata m;
  std::istringstream in(text);
  std::string line;
  bool listed = false, in_list = false;
  std::size_t list_indent = 0;
  while (std::getline(in, line)) {
    const std::size_t indent = line.find_first_not_of(' ');
    const std::string body = trim(line);
    if (body.empty() || body[0] == '#') continue;
    if (in_list && body[0] == '-' && indent >= list_indent) {
      if (!unquote(body.substr(1)).empty())
        m.relative_file_paths.push_back(unquote(body.substr(1)));
      continue;
    }
    in_list = false;
    const auto colon = body.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = body.substr(0, colon), value = unquote(body.substr(colon + 1));
    if (key == "storage_identifier")
      m.storage_identifier = value;
    else if (key == "compression_format")
      m.compression_format = value;
    else if (key == "compression_mode")
      m.compression_mode = value;
    else if (key == "relative_file_paths") {
      listed = true;
      in_list = value.empty();
      list_indent = indent;
      if (!value.empty() && value[0] == '[') m.relative_file_paths = flowList(value);
    }
  }
  if (!listed || m.relative_file_paths.empty())
    throw InputError(
        file, "relative_file_paths",
        listed ? "lists no storage file" : "missing: the metadata names no storage file",
        kReindexRemedy);
  // not written by the oldest rosbag2 versions: the file names tell
  if (m.storage_identifier.empty()) {
    const std::string ext = fs::path(m.relative_file_paths.front()).extension().string();
    m.storage_identifier = ext == ".mcap" ? "mcap" : ext == ".db3" ? "sqlite3" : "";
  }
  if (m.storage_identifier != "mcap" && m.storage_identifier != "sqlite3")
    throw InputError(
        file, "storage_identifier",
        "'" + m.storage_identifier + "' is not a storage lidarcal reads (sqlite3, mcap)",
        "`ros2 bag convert` writes an MCAP or SQLite copy");
  return m;
}

Rosbag2::Rosbag2(const fs::path& bag) {
  std::error_code ec;
  if (fs::is_directory(bag, ec)) {
    Rosbag2Metadata meta;
    for (const fs::path& file : listedFiles(bag, meta))
      files_.push_back(openFile(file, meta.storage_identifier));
  } else {
    files_.push_back(openFile(bag, storageOf(bag)));
  }
  std::map<std::string, Rosbag2Topic> merged;
  for (const auto& f : files_)
    for (const Rosbag2Topic& t : f->topics()) {
      auto [it, fresh] = merged.emplace(t.topic.topic, t);
      if (!fresh) it->second.topic.messages += t.topic.messages;
    }
  for (auto& [name, t] : merged) topics_.push_back(std::move(t));
}

std::vector<BagTopic> Rosbag2::bagTopics() const {
  std::vector<BagTopic> out;
  for (const auto& t : topics_) out.push_back(t.topic);
  return out;
}

void Rosbag2::forEach(const std::set<std::string>& topics,
                      const Rosbag2MessageCallback& on_message) const {
  for (const auto& f : files_)
    if (!f->forEach(topics, on_message)) return;
}

}  // namespace lidarcal::io
