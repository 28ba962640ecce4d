// SPDX-License-Identifier: BSD-3-Clause
// Line reading of plain and gzip files; damaged gzip is reported.

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "import_test_util.hpp"
#include "io/line_reader.hpp"
#include "io/text_fields.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;

std::vector<std::string> readAll(const std::filesystem::path& file) {
  LineReader r(file);
  std::vector<std::string> lines;
  for (std::string line; r.next(line);) {
    lines.push_back(line);
    EXPECT_EQ(r.lineNumber(), lines.size());
  }
  EXPECT_DOUBLE_EQ(r.progress(), 1.0);
  return lines;
}

TEST(LineReader, PlainAndGzipGiveTheSameLines) {
  TempDir dir;
  const std::string long_line(100000, 'x');
  const std::string text = "first\r\n\nthird " + long_line + "\nlast without newline";
  const std::vector<std::string> expected = {"first", "", "third " + long_line,
                                             "last without newline"};
  test::writeFile(dir / "a.txt", text);
  test::writeGzip(dir / "a.txt.gz", text);
  EXPECT_EQ(readAll(dir / "a.txt"), expected);
  EXPECT_EQ(readAll(dir / "a.txt.gz"), expected);
  EXPECT_FALSE(LineReader(dir / "a.txt").compressed());
  EXPECT_TRUE(LineReader(dir / "a.txt.gz").compressed());
}

TEST(LineReader, ConcatenatedGzipMembersReadAsOneFile) {
  TempDir dir;
  test::writeGzip(dir / "a.gz", "one\ntwo\n");
  test::writeGzip(dir / "b.gz", "three\n");
  test::writeFile(dir / "ab.gz", test::readFile(dir / "a.gz") + test::readFile(dir / "b.gz"));
  EXPECT_EQ(readAll(dir / "ab.gz"), (std::vector<std::string>{"one", "two", "three"}));
}

TEST(LineReader, TruncatedGzipIsAnError) {
  TempDir dir;
  std::string text;
  for (int i = 0; i < 20000; ++i) text += "line " + std::to_string(i * 7919 % 10007) + "\n";
  test::writeGzip(dir / "a.gz", text);
  const std::string gz = test::readFile(dir / "a.gz");
  test::writeFile(dir / "cut.gz", gz.substr(0, gz.size() - 100));
  try {
    readAll(dir / "cut.gz");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gzip data is damaged or cut short"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("cut.gz"), std::string::npos) << e.what();
  }
}

TEST(LineReader, MissingFileOrDirectoryIsAnError) {
  TempDir dir;
  EXPECT_THROW(LineReader(dir / "nope.txt"), InputError);
  EXPECT_THROW(LineReader(dir.path()), InputError);
}

TEST(TextFields, SplitAndParse) {
  std::vector<std::string_view> f;
  splitWhitespace("  FLASER 3\t1.0  2 ", f);
  EXPECT_EQ(f, (std::vector<std::string_view>{"FLASER", "3", "1.0", "2"}));
  splitCommas(" 1.5, 2 ,,x ", f);
  EXPECT_EQ(f, (std::vector<std::string_view>{"1.5", "2", "", "x"}));
  splitCommas("   ", f);
  EXPECT_TRUE(f.empty());
  double v = 0;
  EXPECT_TRUE(parseNumber("+1.5e2", v));
  EXPECT_EQ(v, 150.0);
  EXPECT_TRUE(parseNumber("-0.25", v));
  EXPECT_EQ(v, -0.25);
  EXPECT_TRUE(parseNumber("nan", v));
  EXPECT_TRUE(std::isnan(v));
  for (const char* bad : {"", "1.5x", "abc", " 1", "1,5", "+"})
    EXPECT_FALSE(parseNumber(bad, v)) << bad;
}

}  // namespace
}  // namespace lidarcal::io
