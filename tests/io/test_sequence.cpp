// SPDX-License-Identifier: BSD-3-Clause
// Sequences: file order, grouping into stops, metadata, bad directories.

#include <algorithm>
#include <cstdint>
#include <cstring>

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "io/sequence.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;

// The InputError openSequence raises for `dir` (a test failure when it opens without one).
InputError openError(const std::filesystem::path& dir) {
  try {
    openSequence(dir);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << dir << ": opened without an error";
  return InputError(dir.string(), "", "no error");
}
namespace fs = std::filesystem;

TEST(GroupStops, ConsecutiveEqualViewpointsFormOneStop) {
  // stop 0 (within tolerance)
  const std::vector<Pose2> v = {{0, 0, 0},
                                {0.0004, 0, 0},
                                {0, 0.0009, deg2rad(0.009)},
                                {0.3, 0, 0},
                                {0.3, 0, 0},              // stop 1
                                {0.3, 0, deg2rad(0.02)},  // heading differs: stop 2
                                {0, 0, 0}};               // back at start: new stop 3
  const auto stops = groupStops(v);
  ASSERT_EQ(stops.size(), 4u);
  EXPECT_EQ(std::vector<std::size_t>(stops[0].scans.begin(), stops[0].scans.end()),
            (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(std::vector<std::size_t>(stops[1].scans.begin(), stops[1].scans.end()),
            (std::vector<std::size_t>{3, 4}));
  EXPECT_EQ(std::vector<std::size_t>(stops[2].scans.begin(), stops[2].scans.end()),
            (std::vector<std::size_t>{5}));
  EXPECT_EQ(std::vector<std::size_t>(stops[3].scans.begin(), stops[3].scans.end()),
            (std::vector<std::size_t>{6}));
}

TEST(GroupStops, PositionJustBeyondOneMillimetreStartsANewStop) {
  const auto stops = groupStops({{0, 0, 0}, {0.0011, 0, 0}});
  EXPECT_EQ(stops.size(), 2u);
}

TEST(GroupStops, HeadingWrapsAroundPi) {
  const auto stops = groupStops({{0, 0, kPi - 1e-6}, {0, 0, -kPi + 1e-6}});
  EXPECT_EQ(stops.size(), 1u);
}

Scan tinyScan(const Pose2& vp) {
  Scan s;
  s.viewpoint = vp;
  s.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  s.cloud->resize(4);
  for (auto& p : *s.cloud) p.x = 1.0f, p.y = 0.5f, p.z = 0.0f;
  return s;
}

TEST(GroupStops, ListedStartsSplitEqualViewpoints) {
  const std::vector<Pose2> v(5, Pose2{1.0, 2.0, 0.5});
  const auto stops = groupStops(v, StopTolerance{}, {2, 3});
  ASSERT_EQ(stops.size(), 3u);
  EXPECT_EQ(stops[0].scans.size(), 2u);
  EXPECT_EQ(stops[1].scans.front(), 2u);
  EXPECT_EQ(stops[1].scans.size(), 1u);
  EXPECT_EQ(stops[2].scans.front(), 3u);
  EXPECT_EQ(stops[2].scans.size(), 2u);
}

TEST(OpenSequence, StopStartsInSequenceJsonBeginStopsAtOnePose) {
  // Recordings taken apart at one pose (import --stop-per-input): the scans listed in
  // stop_starts begin stops although every VIEWPOINT is the same; names survive a rewrite.
  TempDir dir;
  for (int i = 0; i < 6; ++i)
    writeScan(dir / scanFileName(static_cast<std::size_t>(i)), tinyScan({0, 0, 0}));
  SequenceMeta meta;
  meta.stop_starts = {scanFileName(2), scanFileName(5)};
  writeSequenceMeta(dir / "sequence.json", meta);
  const Sequence seq = openSequence(dir.path());
  ASSERT_EQ(seq.stops.size(), 3u);
  EXPECT_EQ(seq.stops[1].scans.front(), 2u);
  EXPECT_EQ(seq.stops[2].scans.front(), 5u);
  EXPECT_EQ(seq.stopOf(4), 1u);
  EXPECT_EQ(readSequenceMeta(dir / "sequence.json").stop_starts, meta.stop_starts);

  meta.stop_starts = {scanFileName(2), "scan_000009.pcd"};  // no such scan
  writeSequenceMeta(dir / "sequence.json", meta);
  EXPECT_NE(std::string(openError(dir.path()).what()).find("stop_starts"), std::string::npos);
  meta.stop_starts = {"scan_000001x.pcd"};  // between two scans, not one of them
  writeSequenceMeta(dir / "sequence.json", meta);
  EXPECT_NE(std::string(openError(dir.path()).what()).find("not a scan"), std::string::npos);
  test::writeFile(dir / "sequence.json",
                  R"({"stop_starts": ["scan_000005.pcd", "scan_000002.pcd"]})");
  EXPECT_NE(std::string(openError(dir.path()).what()).find("sorted"), std::string::npos);
}

TEST(OpenSequence, ListsPcdFilesLexicographicallyAndGroupsStops) {
  TempDir dir;
  writeScan(dir / "b_002.pcd", tinyScan({0.3, 0, 0}));
  writeScan(dir / "b_000.pcd", tinyScan({0, 0, 0}));
  writeScan(dir / "b_001.pcd", tinyScan({0, 0, 0}));
  test::writeFile(dir / "notes.txt", "not a scan");
  writeSequenceMeta(dir / "sequence.json", SequenceMeta{std::string("X"), 0.12, 0.2, 6.0, 4, {}});
  const Sequence seq = openSequence(dir.path());
  ASSERT_EQ(seq.scans.size(), 3u);
  EXPECT_EQ(seq.scans[0].name(), "b_000.pcd");
  EXPECT_EQ(seq.scans[2].name(), "b_002.pcd");
  ASSERT_EQ(seq.stops.size(), 2u);
  EXPECT_EQ(seq.stopOf(0), 0u);
  EXPECT_EQ(seq.stopOf(1), 0u);
  EXPECT_EQ(seq.stopOf(2), 1u);
  EXPECT_THROW(seq.stopOf(3), std::out_of_range);
  ASSERT_TRUE(seq.meta.landmark_radius_m);
  EXPECT_DOUBLE_EQ(*seq.meta.landmark_radius_m, 0.12);
  EXPECT_EQ(*seq.meta.sensor_name, "X");
}

// The compact header list gives back, field by field, what readScanHeader read from each file.
TEST(OpenSequence, TheHeaderListGivesBackEveryHeaderAsRead) {
  TempDir dir;
  Scan a = tinyScan({0.25, -1.5, 0.3});
  a.has_intensity = true;
  Scan b = tinyScan({0.25, -1.5, 0.3});
  b.cloud->resize(5);
  b.labels.assign(5, 7u);
  writeScan(dir / "scan_000.pcd", a);
  writeScan(dir / "scan_001.pcd", b, PcdEncoding::ascii);
  writeScan(dir / "a_much_longer_file_name_than_the_others.pcd", tinyScan({1, 2, -0.5}));
  const Sequence seq = openSequence(dir.path());
  ASSERT_EQ(seq.scans.size(), 3u);
  std::size_t n = 0;
  for (const ScanHeader& h : seq.scans) {
    const ScanHeader r = readScanHeader(seq.dir / h.name());
    EXPECT_EQ(h.path, r.path);
    EXPECT_EQ(h.viewpoint.x_m, r.viewpoint.x_m);
    EXPECT_EQ(h.viewpoint.y_m, r.viewpoint.y_m);
    EXPECT_EQ(h.viewpoint.yaw_rad, r.viewpoint.yaw_rad);
    EXPECT_EQ(h.points, r.points);
    EXPECT_EQ(h.has_intensity, r.has_intensity);
    EXPECT_EQ(h.has_label, r.has_label);
    EXPECT_EQ(h.binary, r.binary);
    ++n;
  }
  EXPECT_EQ(n, 3u);
  EXPECT_EQ(seq.scans.front().name(), "a_much_longer_file_name_than_the_others.pcd");
  EXPECT_EQ(seq.scans.back().points, 5u);
  EXPECT_TRUE(seq.scans[1].has_intensity);
  EXPECT_TRUE(seq.scans[2].has_label);
  EXPECT_FALSE(seq.scans[2].binary);
  EXPECT_THROW(seq.scans.at(3), std::out_of_range);
  ScanList other = seq.scans;
  ScanHeader elsewhere = seq.scans[0];
  elsewhere.path = "/elsewhere/scan.pcd";
  EXPECT_THROW(other.push_back(elsewhere), std::invalid_argument);
}

std::uint64_t bitsOf(double v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

/// Field by field; the doubles bit for bit (-0.0 is not 0.0).
bool sameHeader(const ScanHeader& a, const ScanHeader& b) {
  return a.path == b.path && bitsOf(a.viewpoint.x_m) == bitsOf(b.viewpoint.x_m) &&
         bitsOf(a.viewpoint.y_m) == bitsOf(b.viewpoint.y_m) &&
         bitsOf(a.viewpoint.yaw_rad) == bitsOf(b.viewpoint.yaw_rad) && a.points == b.points &&
         a.has_intensity == b.has_intensity && a.has_label == b.has_label && a.binary == b.binary;
}

std::string describe(const ScanHeader& h) {
  return h.path + " vp " + std::to_string(h.viewpoint.x_m) + " " + std::to_string(h.viewpoint.y_m) +
         " " + std::to_string(h.viewpoint.yaw_rad) + " points " + std::to_string(h.points) +
         " flags " + std::to_string(h.has_intensity) + std::to_string(h.has_label) +
         std::to_string(h.binary);
}

// Numbered names with gaps are kept as one run per contiguous block and give back every path in
// lexicographic order; directories, hidden files and other files are skipped as before.
TEST(OpenSequence, NumberedNamesWithGapsComeBackInOrder) {
  TempDir dir;
  const std::vector<std::string> names = {"scan_000.pcd", "scan_001.pcd", "scan_002.pcd",
                                          "scan_007.pcd", "scan_008.pcd", "scan_009.pcd",
                                          "scan_020.pcd"};
  for (auto it = names.rbegin(); it != names.rend(); ++it)
    writeScan(dir / *it, tinyScan({0, 0, 0}));
  fs::create_directory(dir / "scan_003.pcd");
  test::writeFile(dir / ".scan_004.pcd", "not a scan");
  test::writeFile(dir / "notes.txt", "not a scan");
  const Sequence seq = openSequence(dir.path());
  ASSERT_EQ(seq.scans.size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    EXPECT_EQ(seq.scans.path(i), (dir / names[i]).string());
    EXPECT_EQ(seq.scans[i].name(), names[i]);
  }
  EXPECT_EQ(seq.scans.nameRuns(), 3u);
  EXPECT_EQ(seq.scans.headerRuns(), 1u);
  for (std::size_t i = 0; i < names.size(); ++i) EXPECT_EQ(seq.stopOf(i), 0u);
  EXPECT_THROW(seq.scans.path(names.size()), std::out_of_range);
}

// Names of more than one pattern (or none) are read as before: every name, lexicographic order.
TEST(OpenSequence, MixedPatternsReadAsTheNamesInLexicographicOrder) {
  const std::vector<std::vector<std::string>> cases = {
      {"a_01.pcd", "a_02.pcd", "a_03.pcd", "a_04.pcd", "a_05.pcd", "a_06.pcd", "a_07.pcd",
       "a_08.pcd", "a_09.pcd", "a_10.pcd", "a_11.pcd", "b_1.pcd", "zz.pcd"},
      {"s_1.pcd", "s_20.pcd", "s_300.pcd"},   // one prefix, widths that still sort
      {"t_01.pcd", "t_02.pcd", "t_1.5.pcd"},  // a decimal fraction is no scan number
      {"n_18446744073709551615.pcd", "n_99999999999999999999.pcd"},  // beyond 64 bits
  };
  for (const auto& names : cases) {
    TempDir dir;
    for (auto it = names.rbegin(); it != names.rend(); ++it)
      writeScan(dir / *it, tinyScan({0, 0, 0}));
    std::vector<std::string> sorted = names;
    std::sort(sorted.begin(), sorted.end());
    const Sequence seq = openSequence(dir.path());
    ASSERT_EQ(seq.scans.size(), sorted.size());
    for (std::size_t i = 0; i < sorted.size(); ++i)
      EXPECT_EQ(seq.scans.path(i), (dir / sorted[i]).string());
    EXPECT_EQ(seq.scans.nameRuns(), 0u) << names.front();
  }
}

// When the names leave the one pattern after many fit it, the scan-number checks run as before.
TEST(OpenSequence, ScanNumberChecksRunWhenTheNamesLeaveThePattern) {
  {
    TempDir dir;
    for (std::size_t i = 0; i < 20; ++i)
      test::writeFile(dir / scanFileName(i), "headers are not read");
    test::writeFile(dir / "scan_3.pcd", "headers are not read");
    const std::string what = openError(dir.path()).what();
    EXPECT_NE(what.find("scan_3.pcd"), std::string::npos) << what;
    EXPECT_NE(what.find("same scan number as scan_000003.pcd"), std::string::npos) << what;
  }
  {
    TempDir dir;
    for (std::size_t i = 10; i < 30; ++i)
      test::writeFile(dir / ("s_" + std::to_string(i) + ".pcd"), "x");
    test::writeFile(dir / "s_2.pcd", "x");
    const std::string what = openError(dir.path()).what();
    EXPECT_NE(what.find("s_2.pcd: sorts after s_19.pcd"), std::string::npos) << what;
  }
}

// Viewpoint, point count and flags change at arbitrary scans (and come back to earlier values):
// each header read back is the file's, and equal neighbours share a run.
TEST(OpenSequence, HeadersThatChangeAnywhereComeBackAsRead) {
  TempDir dir;
  const Pose2 a{0.5, -0.25, 0.1}, b{0.5, -0.25, 0.1 + 1e-12}, z{0, 0, 0}, mz{-0.0, 0, -0.0};
  struct Spec {
    Pose2 vp;
    std::size_t points;
    bool intensity, label;
    PcdEncoding enc;
  };
  const std::vector<Spec> specs = {
      {a, 4, false, false, PcdEncoding::binary},
      {a, 4, false, false, PcdEncoding::binary},
      {a, 5, false, false, PcdEncoding::binary},  // points
      {a, 5, true, false, PcdEncoding::binary},   // intensity
      {a, 5, true, false, PcdEncoding::ascii},    // encoding
      {a, 5, true, true, PcdEncoding::ascii},     // label
      {b, 5, true, true, PcdEncoding::ascii},     // yaw, in the last bits
      {b, 5, true, true, PcdEncoding::ascii},
      {a, 4, false, false, PcdEncoding::binary},  // back to the first values
      {z, 4, false, false, PcdEncoding::binary},
      {mz, 4, false, false, PcdEncoding::binary},
      {z, 4, false, false, PcdEncoding::binary},
      {z, 4, false, false, PcdEncoding::binary},
  };
  for (std::size_t i = 0; i < specs.size(); ++i) {
    Scan s = tinyScan(specs[i].vp);
    s.cloud->resize(specs[i].points);
    s.has_intensity = specs[i].intensity;
    if (specs[i].label) s.labels.assign(specs[i].points, 3u);
    writeScan(dir / scanFileName(i), s, specs[i].enc);
  }
  const Sequence seq = openSequence(dir.path());
  ASSERT_EQ(seq.scans.size(), specs.size());
  std::size_t runs = 0;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const ScanHeader r = readScanHeader(dir / scanFileName(i));
    EXPECT_TRUE(sameHeader(seq.scans[i], r)) << describe(seq.scans[i]) << " read " << describe(r);
    if (i == 0) {
      ++runs;
    } else {
      ScanHeader prev = readScanHeader(dir / scanFileName(i - 1));
      prev.path = r.path;
      if (!sameHeader(prev, r)) ++runs;
    }
  }
  EXPECT_GE(runs, 7u);  // more when the file keeps the last bits of b's yaw and the sign of -0
  EXPECT_EQ(seq.scans.headerRuns(), runs);
  EXPECT_EQ(seq.scans.nameRuns(), 1u);
  std::size_t n = 0;
  for (const ScanHeader& h : seq.scans)
    EXPECT_TRUE(sameHeader(h, readScanHeader(dir / scanFileName(n++))));
  EXPECT_EQ(n, specs.size());
}

// push_back keeps every header, whether the names stay numbered or not.
TEST(ScanList, PushBackGivesBackEveryHeader) {
  const std::vector<std::string> names = {"scan_0001.pcd", "scan_0002.pcd", "scan_0003.pcd",
                                          "scan_0010.pcd", "scan_0005.pcd", "scan_0006.pcd",
                                          "other.pcd",     "scan_0011.pcd"};
  std::vector<ScanHeader> headers;
  for (std::size_t i = 0; i < names.size(); ++i) {
    ScanHeader h;
    h.path = "/data/run/" + names[i];
    h.viewpoint = i < 3 ? Pose2{1, 2, 0.5} : i == 5 ? Pose2{-0.0, 2, 0.5} : Pose2{0, 2, 0.5};
    h.points = i == 4 ? 360 : 361;
    h.has_intensity = i % 2 == 0;
    h.has_label = i == 7;
    h.binary = i != 6;
    headers.push_back(h);
  }
  ScanList numbered, mixed;
  for (std::size_t i = 0; i < names.size(); ++i) {
    mixed.push_back(headers[i]);
    if (i != 6) numbered.push_back(headers[i]);
    ASSERT_EQ(mixed.size(), i + 1);
    for (std::size_t k = 0; k <= i; ++k)
      EXPECT_TRUE(sameHeader(mixed[k], headers[k])) << "after " << i << ": " << describe(mixed[k]);
  }
  EXPECT_EQ(mixed.nameRuns(), 0u);
  ASSERT_EQ(numbered.size(), names.size() - 1);
  for (std::size_t k = 0; k < numbered.size(); ++k)
    EXPECT_TRUE(sameHeader(numbered[k], headers[k < 6 ? k : k + 1])) << describe(numbered[k]);
  EXPECT_EQ(numbered.nameRuns(), 4u);  // 1-3, 10, 5-6, 11
  EXPECT_EQ(numbered.front().name(), "scan_0001.pcd");
  EXPECT_EQ(numbered.back().name(), "scan_0011.pcd");
  EXPECT_EQ(mixed.at(6).name(), "other.pcd");
}

// The names constructor and numbered(): the names as given; headers only in index order.
TEST(ScanList, NamesAndHeadersAsGiven) {
  const std::vector<std::string> names = {
      "n_18446744073709551614.pcd", "n_18446744073709551615.pcd", "n_00000000000000000000.pcd",
      "n_00000000000000000001.pcd"};
  const ScanList l("/d/", names);
  ASSERT_EQ(l.size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) EXPECT_EQ(l.path(i), "/d/" + names[i]);
  EXPECT_EQ(l.nameRuns(), 2u);  // no run across the wrap to 0
  EXPECT_THROW(l[0], std::logic_error);

  ScanList m = ScanList::numbered("/e/", "x", 3, {4, 5, 9, 1, 2});
  const std::vector<std::string> expected = {"/e/x004.pcd", "/e/x005.pcd", "/e/x009.pcd",
                                             "/e/x001.pcd", "/e/x002.pcd"};
  ASSERT_EQ(m.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(m.path(i), expected[i]);
  EXPECT_EQ(m.nameRuns(), 3u);
  EXPECT_THROW(ScanList::numbered("/e/", "x", 3, {1000}), std::invalid_argument);

  ScanHeader h;
  h.path = expected[1];
  EXPECT_THROW(m.setHeader(1, h), std::invalid_argument);  // scan 0 first
  h.path = expected[0];
  m.setHeader(0, h);
  EXPECT_THROW(m.setHeader(0, h), std::invalid_argument);  // once
  EXPECT_THROW(m.push_back(h), std::invalid_argument);     // scans 1.. have no header yet
  for (std::size_t i = 1; i < expected.size(); ++i) {
    h.path = expected[i];
    h.points = i;
    m.setHeader(i, h);
  }
  h.path = "/e/x003.pcd";
  m.push_back(h);
  EXPECT_EQ(m.back().path, "/e/x003.pcd");
  EXPECT_EQ(m[2].points, 2u);
  EXPECT_EQ(m[0].points, 0u);
  EXPECT_EQ(m.headerRuns(), 5u);
}

TEST(OpenSequence, EmptyDirectoryIsAnError) {
  TempDir dir;
  EXPECT_NE(std::string(openError(dir.path()).what()).find("holds no .pcd file"),
            std::string::npos);
}

TEST(OpenSequence, MissingDirectoryIsAnError) {
  EXPECT_THROW(openSequence("/nonexistent/lidarcal"), InputError);
}

TEST(OpenSequence, MalformedSequenceJsonNamesTheField) {
  TempDir dir;
  writeScan(dir / "a.pcd", tinyScan({0, 0, 0}));
  test::writeFile(dir / "sequence.json", R"({"landmark_radius_m": -1})");
  const InputError radius = openError(dir.path());
  EXPECT_EQ(radius.item(), "landmark_radius_m");
  EXPECT_NE(radius.problem().find("positive"), std::string::npos);
  test::writeFile(dir / "sequence.json", "{ \"beams\": 3,\n oops }");
  const InputError syntax = openError(dir.path());
  EXPECT_NE(syntax.item().find("line 2"), std::string::npos) << syntax.what();
}

}  // namespace
}  // namespace lidarcal::io
