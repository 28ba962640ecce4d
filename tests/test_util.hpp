// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shared test helpers: temporary directories, running the `lidarcal` binary, hashing files.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace lidarcal::test {

namespace fs = std::filesystem;

/// A fresh directory under the system temp dir, removed at scope exit.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "lidarcal-test-";
    if (info) name += std::string(info->test_suite_name()) + "-" + info->name();
    for (char& c : name)
      if (c == '/') c = '_';
    path_ = fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& p) const { return path_ / p; }

 private:
  fs::path path_;
};

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void writeFile(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << bytes;
}

/// Runs `lidarcal <args>` (args are passed to the shell as written) after an optional shell
/// `prefix` (e.g. `ulimit -f 0`), and captures its exit code, stdout and stderr.
inline CliResult runCliPrefixed(const std::string& prefix, const std::string& args) {
  static int counter = 0;
  const fs::path base = fs::temp_directory_path() / ("lidarcal-cli-" + std::to_string(::getpid()) +
                                                     "-" + std::to_string(counter++));
  const std::string cmd = (prefix.empty() ? std::string() : prefix + "; ") + "exec '" +
                          LIDARCAL_EXE + "' " + args + " >'" + base.string() + ".out' 2>'" +
                          base.string() + ".err'";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readFile(base.string() + ".out");
  r.err = readFile(base.string() + ".err");
  fs::remove(base.string() + ".out");
  fs::remove(base.string() + ".err");
  return r;
}

/// Runs `lidarcal <args>` and captures its output.
inline CliResult runCli(const std::string& args) { return runCliPrefixed("", args); }

/// Content of every regular file under `dir`, keyed by relative path (for "input unchanged"
/// and "same bytes" checks).
inline std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = readFile(e.path());
  return files;
}

/// Expects `got` to hold the files of `expected`, byte for byte (a mismatch names the file but does
/// not print the bytes: a PNG would flood the log).
inline void expectSameFiles(const std::map<std::string, std::string>& expected,
                            const std::map<std::string, std::string>& got) {
  EXPECT_EQ(got.size(), expected.size());
  for (const auto& [name, bytes] : expected) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(got.count(name)) << "missing";
    EXPECT_TRUE(got.at(name) == bytes) << "differs";
  }
}

inline fs::path sourceDir() { return LIDARCAL_TEST_SOURCE_DIR; }
inline fs::path sharedData() { return LIDARCAL_SHARED_DATA; }

}  // namespace lidarcal::test
