// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Test-side writers of ROS 2 bags, built straight from the specifications and independent of the
// reader under test: CDR serialisation of LaserScan, Odometry and TFMessage (cdr_test_writer.hpp:
// CORBA 3.3 Part 2 §9.3, DDS-XTypes encapsulation header), MCAP files record by record
// (https://mcap.dev/spec), chunks compressed with libzstd / liblz4 directly, and rosbag2 SQLite
// files through the sqlite3 C API. Also used to write the fuzz seeds (tests/fuzz/corpus/mcap, cdr).

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <lz4frame.h>
#include <sqlite3.h>
#include <zlib.h>
#include <zstd.h>

#include "io/cdr_test_writer.hpp"

namespace lidarcal::test {

/// The fields of a LaserScan the tests choose.
struct TestScan {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string frame_id = "laser";
  float angle_min = -1.5f, angle_increment = 0.25f;
  float range_min = 0.15f, range_max = 12.0f;
  std::vector<float> ranges, intensities;
};

/// Scan k of `beams` beams as the node and bag tests record it: readings 0.2 + 0.11 (i mod 100)
/// + 0.01 k metres, intensities i mod 7, angles from -3.1 rad by 0.06 rad; beams 1-5 hold what is
/// not a reading (inf, NaN, 0, below range_min, above range_max).
inline TestScan recordedScan(int k, std::size_t beams) {
  TestScan s;
  s.sec = 100 + k;
  s.nanosec = 1000u * static_cast<std::uint32_t>(k);
  s.angle_min = -3.1f;
  s.angle_increment = 0.06f;
  for (std::size_t i = 0; i < beams; ++i) {
    s.ranges.push_back(0.2f + 0.11f * static_cast<float>(i % 100) + 0.01f * static_cast<float>(k));
    s.intensities.push_back(static_cast<float>(i % 7));
  }
  const float not_readings[] = {std::numeric_limits<float>::infinity(),
                                std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.1f, 12.5f};
  for (std::size_t i = 0; i < 5 && i + 1 < beams; ++i) s.ranges[i + 1] = not_readings[i];
  return s;
}

inline std::string laserScanCdr(const TestScan& s, bool big_endian = false) {
  CdrWriter w(big_endian);
  w.i32(s.sec);
  w.u32(s.nanosec);
  w.str(s.frame_id);
  w.f32(s.angle_min);
  // angle_max
  w.f32(s.angle_min +
        s.angle_increment * static_cast<float>(s.ranges.empty() ? 0 : s.ranges.size() - 1));
  w.f32(s.angle_increment);
  w.f32(0.0001f);  // time_increment
  w.f32(0.1f);     // scan_time
  w.f32(s.range_min);
  w.f32(s.range_max);
  w.f32seq(s.ranges);
  w.f32seq(s.intensities);
  return w.bytes();
}

/// nav_msgs/msg/Odometry at (x, y) with heading yaw (rotation about z); covariance and twist zero.
inline std::string odometryCdr(std::int32_t sec, std::uint32_t nanosec, double x, double y,
                               double yaw, bool big_endian = false) {
  CdrWriter w(big_endian);
  w.i32(sec);
  w.u32(nanosec);
  w.str("odom");
  w.str("base_link");
  for (double v : {x, y, 0.0, 0.0, 0.0, std::sin(yaw / 2), std::cos(yaw / 2)}) w.f64(v);
  for (int i = 0; i < 36 + 6 + 36; ++i) w.f64(0.0);  // pose covariance, twist, twist covariance
  return w.bytes();
}

/// One geometry_msgs/msg/TransformStamped of a tf2_msgs/msg/TFMessage: planar (x, y, yaw).
struct TestTransform {
  std::int32_t sec;
  std::string parent, child;
  double x, y, yaw;
};
inline std::string tfMessageCdr(const std::vector<TestTransform>& transforms,
                                bool big_endian = false) {
  CdrWriter w(big_endian);
  w.u32(static_cast<std::uint32_t>(transforms.size()));
  for (const auto& t : transforms) {
    w.i32(t.sec);
    w.u32(0);
    w.str(t.parent);
    w.str(t.child);
    for (double v : {t.x, t.y, 0.0, 0.0, 0.0, std::sin(t.yaw / 2), std::cos(t.yaw / 2)}) w.f64(v);
  }
  return w.bytes();
}

// ---- MCAP (https://mcap.dev/spec): little-endian integers, uint32-prefixed strings ----
inline std::string le(std::uint64_t v, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += static_cast<char>(v >> (8 * i));
  return s;
}
inline std::string mstr(const std::string& s) { return le(s.size(), 4) + s; }
inline std::string record(std::uint8_t op, const std::string& content) {
  return std::string(1, static_cast<char>(op)) + le(content.size(), 8) + content;
}
inline std::string schemaRecord(std::uint16_t id, const std::string& name) {
  return record(0x03, le(id, 2) + mstr(name) + mstr("ros2msg") + mstr("# definition"));
}
inline std::string channelRecord(std::uint16_t id, std::uint16_t schema, const std::string& topic,
                                 const std::string& enc = "cdr") {
  return record(0x04, le(id, 2) + le(schema, 2) + mstr(topic) + mstr(enc) + le(0, 4));
}
inline std::string messageRecord(std::uint16_t channel, std::uint64_t log_time,
                                 const std::string& data) {
  return record(0x05, le(channel, 2) + le(0, 4) + le(log_time, 8) + le(log_time, 8) + data);
}

inline std::string compress(const std::string& raw, const std::string& compression) {
  std::string out;
  if (compression == "zstd") {
    out.resize(ZSTD_compressBound(raw.size()));
    const std::size_t n = ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), 3);
    EXPECT_FALSE(ZSTD_isError(n));
    out.resize(n);
  } else if (compression == "lz4") {
    out.resize(LZ4F_compressFrameBound(raw.size(), nullptr));
    const std::size_t n =
        LZ4F_compressFrame(out.data(), out.size(), raw.data(), raw.size(), nullptr);
    EXPECT_FALSE(LZ4F_isError(n));
    out.resize(n);
  } else {
    out = raw;
  }
  return out;
}

/// A Chunk record holding `records` (start/end times given by the test).
inline std::string chunkRecord(const std::string& records, const std::string& compression,
                               std::uint64_t start, std::uint64_t end, bool with_crc = true) {
  const std::string packed = compress(records, compression);
  const auto crc = with_crc ? crc32(0L, reinterpret_cast<const Bytef*>(records.data()),
                                    static_cast<uInt>(records.size()))
                            : 0;
  return record(0x06, le(start, 8) + le(end, 8) + le(records.size(), 8) + le(crc, 4) +
                          mstr(compression) + le(packed.size(), 8) + packed);
}

inline const std::string kMcapMagic("\x89MCAP0\r\n", 8);
inline std::string mcapHead() {
  return kMcapMagic + record(0x01, mstr("ros2") + mstr("lidarcal-test"));
}
/// DataEnd, an (empty) summary, Footer and the closing magic.
inline std::string mcapTail() {
  return record(0x0F, le(0, 4)) + record(0x02, le(0, 8) + le(0, 8) + le(0, 4)) + kMcapMagic;
}

// ---- rosbag2 SQLite (.db3) ----
struct Db3Message {
  int topic_id;
  std::int64_t timestamp;
  std::string data;
};
inline void writeDb3(const std::filesystem::path& file,
                     // id, name, type
                     const std::vector<std::tuple<int, std::string, std::string>>& topics,
                     const std::vector<Db3Message>& messages) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  const char* schema =
      "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
      "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
      "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER "
      "NOT NULL, "
      "data BLOB NOT NULL);";
  ASSERT_EQ(sqlite3_exec(db, schema, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  for (const auto& [id, name, type] : topics) {
    const std::string sql = "INSERT INTO topics VALUES(" + std::to_string(id) + ",'" + name +
                            "','" + type + "','cdr','')";
    ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK)
        << sqlite3_errmsg(db);
  }
  sqlite3_stmt* st = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?,?,?)",
                               -1, &st, nullptr),
            SQLITE_OK);
  for (const auto& m : messages) {
    sqlite3_bind_int(st, 1, m.topic_id);
    sqlite3_bind_int64(st, 2, m.timestamp);
    sqlite3_bind_blob(st, 3, m.data.data(), static_cast<int>(m.data.size()), SQLITE_TRANSIENT);
    ASSERT_EQ(sqlite3_step(st), SQLITE_DONE);
    sqlite3_reset(st);
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
}

}  // namespace lidarcal::test
