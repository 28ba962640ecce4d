// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The bad-input catalogue's harness (docs/ERRORS.md): one table row per case. A case prepares
// its inputs under IN, names the command line (placeholders below) and what must happen: the
// exit code, the parts of the message (file, item, problem), a remedy in parentheses, the
// input byte for byte unchanged, and nothing at or beside the output path (no result, no hidden
// `.OUT.partial-*` staging directory, no `.tmp-*` file).
//
// Placeholders in `args`: {IN} the case's input directory, {SEQ} = {IN}/scans, {OUT} the output
// path (in a directory of its own that must stay empty), {FIX} the shared fixtures (good
// sequences and a good model, built once), {SHARED} the measured recordings (../shared/data).
//
// To add the readers and commands of later work (noise-consistency's observations.csv and
// odometry.csv, montecarlo, diagnose): add rows to the table in test_bad_input.cpp, e.g.
//   {"odometry_csv_bad_number", "noise-consistency {SEQ} --odometry {IN}/odom.csv --out {OUT}",
//    [](const Ws& w) { copySequence(w); writeFile(w.in / "odom.csv", "t,x_m\n0,abc\n"); }, 2,
//    {"odom.csv", "line 2", "x_m"}},
// and a row to docs/ERRORS.md.

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace lidarcal::test {

/// A directory of test inputs built once by `build` and shared by every test process (ctest
/// runs each test case in a process of its own): kept in the build tree, keyed by the `lidarcal`
/// binary that made it (rebuilt when lidarcal changes), built under a temporary name and renamed
/// into place, so that two processes building at once do not disturb each other.
inline fs::path cachedFixture(const std::string& name,
                              const std::function<void(const fs::path&)>& build) {
  const fs::path exe = LIDARCAL_EXE;
  const auto stamp =
      static_cast<unsigned long long>(fs::last_write_time(exe).time_since_epoch().count()) ^
      static_cast<unsigned long long>(fs::file_size(exe));
  const fs::path dir = fs::path(LIDARCAL_TEST_FIXTURE_DIR) / (name + "-" + std::to_string(stamp));
  if (fs::exists(dir)) return dir;
  const fs::path tmp = dir.string() + ".tmp-" + std::to_string(::getpid());
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  build(tmp);
  std::error_code ec;
  if (::testing::Test::HasFailure()) {
    fs::remove_all(tmp, ec);
    return dir;
  }
  fs::rename(tmp, dir, ec);  // fails when another process was first: use its copy
  if (ec) fs::remove_all(tmp, ec);
  return dir;
}

/// Where one case runs.
struct Ws {
  fs::path in;   ///< inputs (snapshotted before and after)
  fs::path out;  ///< the output path handed to the command ({OUT})
  fs::path fix;  ///< shared fixtures ({FIX})
  fs::path seq() const { return in / "scans"; }
};

struct BadInputCase {
  std::string name;                        ///< test name (and docs/ERRORS.md row)
  std::string args;                        ///< command line after `lidarcal`, with placeholders
  std::function<void(const Ws&)> prepare;  ///< builds the inputs under Ws::in
  int exit_code = 2;                       ///< 2 bad input, 3 data cannot support the result
  std::vector<std::string> message;        ///< parts the message must contain (file, item, problem)
  /// Runs the command under this shell prefix (e.g. a file-size limit); empty = none.
  std::string shell_prefix;
  /// Returns why the case cannot run here (empty: it runs).
  std::function<std::string(const Ws&)> skip;
  /// Extra inputs outside IN that must stay unchanged (e.g. shared recordings).
  std::function<std::vector<fs::path>(const Ws&)> also_unchanged;
};

inline void PrintTo(const BadInputCase& c, std::ostream* os) { *os << c.name; }

inline std::string replaceAll(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
  return s;
}

/// Every path under `dir` (files, directories, hidden entries), relative.
inline std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return names;
  for (auto it = fs::recursive_directory_iterator(dir, ec);
       it != fs::recursive_directory_iterator(); it.increment(ec))
    names.insert(fs::relative(it->path(), dir).string());
  return names;
}

/// Copies a directory tree.
inline void copyTree(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
}

/// Byte offset of the first data byte of a PCD file (after the DATA line).
inline std::size_t pcdDataOffset(const std::string& bytes) {
  const auto at = bytes.find("\nDATA ");
  return bytes.find('\n', at + 1) + 1;
}

/// Index of the first point of a binary `x y z` PCD whose x is finite.
inline std::size_t firstReturn(const std::string& bytes, std::size_t point_bytes = 12) {
  const std::size_t off = pcdDataOffset(bytes);
  for (std::size_t i = 0; off + (i + 1) * point_bytes <= bytes.size(); ++i) {
    float x;
    std::memcpy(&x, bytes.data() + off + i * point_bytes, 4);
    if (std::isfinite(x)) return i;
  }
  return 0;
}

/// Sets float `field` (0 x, 1 y, 2 z) of point `i` of a binary PCD with 12-byte points.
inline void setFloat(std::string& bytes, std::size_t i, int field, float value) {
  std::memcpy(bytes.data() + pcdDataOffset(bytes) + i * 12 + static_cast<std::size_t>(field) * 4,
              &value, 4);
}

/// Applies `edit` to a file's bytes.
inline void editFile(const fs::path& file, const std::function<void(std::string&)>& edit) {
  std::string bytes = readFile(file);
  edit(bytes);
  writeFile(file, bytes);
}

/// Replaces the header line starting with `key` (e.g. "VIEWPOINT") by `line` (empty: removes it).
inline void setHeaderLine(std::string& bytes, const std::string& key, const std::string& line) {
  const auto at = bytes.find("\n" + key + " ") + 1;
  const auto end = bytes.find('\n', at) + 1;
  bytes.replace(at, end - at, line.empty() ? std::string() : line + "\n");
}

/// True when this process can write into a directory whose mode forbids it (root): then a
/// permission test cannot show anything.
inline bool permissionsAreIgnored(const fs::path& scratch) {
  const fs::path probe = scratch / "perm-probe";
  fs::create_directories(probe);
  ::chmod(probe.c_str(), 0555);
  const bool ignored = ::access(probe.c_str(), W_OK) == 0;
  ::chmod(probe.c_str(), 0755);
  fs::remove_all(probe);
  return ignored;
}

}  // namespace lidarcal::test
