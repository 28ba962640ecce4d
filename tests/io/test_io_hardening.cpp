// SPDX-License-Identifier: BSD-3-Clause
// io-level checks behind docs/ERRORS.md: scan numbering in sequence directories, outputs that
// never replace special files or directories, headers that promise more than the file holds,
// strict true_ranges.csv rows.

#include <sys/stat.h>

#include <cmath>
#include <functional>

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/pcd_scan.hpp"
#include "io/sequence.hpp"
#include "io/true_ranges.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;
namespace fs = std::filesystem;

Scan tinyScan(double x) {
  Scan s;
  s.viewpoint = Pose2{x, 0, 0};
  s.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  s.cloud->resize(3);
  for (auto& p : *s.cloud) p.x = 1.0f, p.y = 0.5f, p.z = 0.0f;
  return s;
}

std::string problemOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SequenceNames, TimeStampsWithFractionsAreNotScanNumbersAndOpenInLexicographicOrder) {
  TempDir dir;
  // 1700000000.25 < 1700000000.5 lexicographically and in time; as integers 25 > 5.
  writeScan(dir / "1700000000.25.pcd", tinyScan(0.0));
  writeScan(dir / "1700000000.5.pcd", tinyScan(0.3));
  writeScan(dir / "1700000001.05.pcd", tinyScan(0.6));
  const Sequence seq = openSequence(dir.path());
  ASSERT_EQ(seq.scans.size(), 3u);
  EXPECT_EQ(seq.scans[1].name(), "1700000000.5.pcd");
}

TEST(SequenceNames, ZeroPaddedNumbersOfGrowingWidthAndSeparatePrefixesAreFine) {
  TempDir dir;
  for (const char* name : {"a_000.pcd", "a_001.pcd", "a_010.pcd", "b_7.pcd", "b_8.pcd", "c.pcd"})
    writeScan(dir / name, tinyScan(0.0));
  EXPECT_EQ(openSequence(dir.path()).scans.size(), 6u);
}

TEST(SequenceNames, OneScanNumberTwiceAndUnpaddedOrderAndUpperCaseAreRefused) {
  {
    TempDir dir;
    writeScan(dir / "scan_0007.pcd", tinyScan(0.0));
    writeScan(dir / "scan_7.pcd", tinyScan(0.0));
    EXPECT_NE(problemOf([&] {
                openSequence(dir.path());
              }).find("scan_7.pcd: has the same scan number as scan_0007.pcd"),
              std::string::npos);
  }
  {
    TempDir dir;
    writeScan(dir / "s9.pcd", tinyScan(0.0));
    writeScan(dir / "s10.pcd", tinyScan(0.0));
    EXPECT_NE(problemOf([&] { openSequence(dir.path()); }).find("s9.pcd: sorts after s10.pcd"),
              std::string::npos);
  }
  {
    TempDir dir;
    writeScan(dir / "a.pcd", tinyScan(0.0));
    writeScan(dir / "b.Pcd", tinyScan(0.0));
    EXPECT_NE(problemOf([&] { openSequence(dir.path()); }).find("b.Pcd: has the extension '.Pcd'"),
              std::string::npos);
  }
}

TEST(SequenceBeams, ScansDisagreeingWithSequenceJsonBeamsAreRefused) {
  TempDir dir;
  writeScan(dir / "a.pcd", tinyScan(0.0));
  Scan four = tinyScan(0.0);
  four.cloud->resize(4);
  writeScan(dir / "b.pcd", four);
  EXPECT_EQ(pointCountRange(openSequence(dir.path())), (std::pair<std::size_t, std::size_t>{3, 4}));
  writeSequenceMeta(dir / "sequence.json", SequenceMeta{{}, {}, {}, {}, 3, {}});
  EXPECT_NE(problemOf([&] {
              openSequence(dir.path());
            }).find("b.pcd: POINTS: has 4 points, but sequence.json says"),
            std::string::npos);
}

TEST(AtomicOutput, NeverReplacesADeviceOrADirectory) {
  struct stat before {};
  ASSERT_EQ(::stat("/dev/null", &before), 0);
  EXPECT_NE(problemOf([] { writeTextAtomically("/dev/null", "x"); }).find("not a regular file"),
            std::string::npos);
  struct stat after {};
  ASSERT_EQ(::stat("/dev/null", &after), 0);
  EXPECT_TRUE(S_ISCHR(after.st_mode));
  EXPECT_EQ(before.st_ino, after.st_ino);
  TempDir dir;
  fs::create_directories(dir / "d");
  EXPECT_NE(problemOf([&] { writeTextAtomically(dir / "d", "x"); }).find("is a directory"),
            std::string::npos);
  EXPECT_NE(problemOf([&] { checkOutputFile(dir / "d", true); }).find("is a directory"),
            std::string::npos);
  test::writeFile(dir / "f", "keep");
  EXPECT_NE(problemOf([&] { checkOutputFile(dir / "f", false); }).find("already exists"),
            std::string::npos);
  EXPECT_NO_THROW(checkOutputFile(dir / "f", true));
  EXPECT_NE(
      problemOf([&] { checkOutputFile(dir / "f" / "g", true); }).find("is a file, not a directory"),
      std::string::npos);
  EXPECT_NE(problemOf([&] {
              StagedDirectory s(dir / "f", true);
            }).find("is a file; the output is a directory"),
            std::string::npos);
  EXPECT_EQ(test::readFile(dir / "f"), "keep");
}

TEST(PcdHeader, PointsThatTheDataCannotHoldAreRefusedBeforeLoading) {
  TempDir dir;
  const std::string head =
      "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nVIEWPOINT 0 0 0 1 0 0 0\n";
  test::writeFile(dir / "a.pcd",
                  head + "WIDTH 100000000\nHEIGHT 1\nPOINTS 100000000\nDATA ascii\n1 2 3\n");
  EXPECT_NE(problemOf([&] { readScan(dir / "a.pcd"); }).find("cannot hold the 100000000 points"),
            std::string::npos);
  test::writeFile(dir / "c.pcd",
                  head + "WIDTH 50000000\nHEIGHT 1\nPOINTS 50000000\nDATA binary_compressed\n" +
                      std::string(64, '\x01'));
  // (the compressed block's own sizes give it away first)
  EXPECT_NE(problemOf([&] {
              readScan(dir / "c.pcd");
            }).find("c.pcd: DATA: the compressed block unpacks to"),
            std::string::npos);
}

TEST(PcdHeader, DataThatPclWouldReadAsMoreHeaderIsRefused) {
  // Found by fuzzing (tests/fuzz/regressions/pcd/): PCL reads on past DATA while lines look
  // like header lines, and loaded a garbage field list instead of x y z.
  const fs::path file =
      test::sourceDir() / "tests/fuzz/regressions/pcd/crash-columns-line-in-binary-data.pcd";
  EXPECT_NE(problemOf([&] {
              readScan(file);
            }).find("DATA: the data begins with a line PCL would read as more header"),
            std::string::npos);
  // Comments and empty lines after DATA are skipped by PCL too and do not matter; binary data
  // that does not read as a keyword loads.
  TempDir dir;
  const std::string head =
      "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n";
  test::writeFile(dir / "a.pcd", head + "1 2 0\n");
  EXPECT_NO_THROW(readScan(dir / "a.pcd"));
  test::writeFile(dir / "b.pcd", head + "WIDTH 7\n1 2 0\n");
  EXPECT_NE(problemOf([&] { readScan(dir / "b.pcd"); }).find("('WIDTH')"), std::string::npos);
}

TEST(TrueRangesCsv, RowsWithBadValuesNameTheColumn) {
  TempDir dir;
  const std::string head = "scan,beam,true_range_m,target,target_id,incidence_rad\n";
  const std::pair<const char*, const char*> cases[] = {
      {"-1,0,1.0,wall,1,0.1", "column scan"},
      {"0,0,1.0,tree,1,0.1", "column target"},
      {"0,0,1.0,wall,1", "expected 6"},
      {"0,0.5,1.0,wall,1,0.1", "column beam"},
      {"0,0,-2,wall,1,0.1", "column true_range_m"}};
  for (const auto& [row, needle] : cases) {
    SCOPED_TRACE(row);
    test::writeFile(dir / "t.csv", head + "0,0,nan,none,0,nan\n" + row + "\n");
    EXPECT_NE(problemOf([&] { readTrueRanges(dir / "t.csv"); }).find(needle), std::string::npos);
  }
  test::writeFile(dir / "t.csv", head + "0,0,nan,none,0,nan\n3,359,2.5,landmark,2,0.25\n");
  const auto rows = readTrueRanges(dir / "t.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_TRUE(std::isnan(rows[0].range_m));
  EXPECT_EQ(rows[1].target, TargetKind::landmark);
  EXPECT_EQ(rows[1].target_id, 2);
}

}  // namespace
}  // namespace lidarcal::io
