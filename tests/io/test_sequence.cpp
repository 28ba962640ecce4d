// Sequences: file order, grouping into stops, metadata, bad directories.

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "io/sequence.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;

TEST(GroupStops, ConsecutiveEqualViewpointsFormOneStop) {
  const std::vector<Pose2> v = {{0, 0, 0}, {0.0004, 0, 0}, {0, 0.0009, deg2rad(0.009)},  // stop 0 (within tolerance)
                                {0.3, 0, 0}, {0.3, 0, 0},                                 // stop 1
                                {0.3, 0, deg2rad(0.02)},                                  // heading differs: stop 2
                                {0, 0, 0}};                                               // back at start: new stop 3
  const auto stops = groupStops(v);
  ASSERT_EQ(stops.size(), 4u);
  EXPECT_EQ(std::vector<std::size_t>(stops[0].scans.begin(), stops[0].scans.end()), (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(std::vector<std::size_t>(stops[1].scans.begin(), stops[1].scans.end()), (std::vector<std::size_t>{3, 4}));
  EXPECT_EQ(std::vector<std::size_t>(stops[2].scans.begin(), stops[2].scans.end()), (std::vector<std::size_t>{5}));
  EXPECT_EQ(std::vector<std::size_t>(stops[3].scans.begin(), stops[3].scans.end()), (std::vector<std::size_t>{6}));
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

TEST(OpenSequence, ListsPcdFilesLexicographicallyAndGroupsStops) {
  TempDir dir;
  writeScan(dir / "b_002.pcd", tinyScan({0.3, 0, 0}));
  writeScan(dir / "b_000.pcd", tinyScan({0, 0, 0}));
  writeScan(dir / "b_001.pcd", tinyScan({0, 0, 0}));
  test::writeFile(dir / "notes.txt", "not a scan");
  writeSequenceMeta(dir / "sequence.json", SequenceMeta{std::string("X"), 0.12, 0.2, 6.0, 4});
  const Sequence seq = openSequence(dir.path());
  ASSERT_EQ(seq.scans.size(), 3u);
  EXPECT_EQ(seq.scans[0].name(), "b_000.pcd");
  EXPECT_EQ(seq.scans[2].name(), "b_002.pcd");
  ASSERT_EQ(seq.stops.size(), 2u);
  EXPECT_EQ(seq.stop_of_scan, (std::vector<std::size_t>{0, 0, 1}));
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

TEST(OpenSequence, EmptyDirectoryIsAnError) {
  TempDir dir;
  try {
    openSequence(dir.path());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("holds no .pcd file"), std::string::npos);
  }
}

TEST(OpenSequence, MissingDirectoryIsAnError) {
  EXPECT_THROW(openSequence("/nonexistent/lidarcal"), InputError);
}

TEST(OpenSequence, MalformedSequenceJsonNamesTheField) {
  TempDir dir;
  writeScan(dir / "a.pcd", tinyScan({0, 0, 0}));
  test::writeFile(dir / "sequence.json", R"({"landmark_radius_m": -1})");
  try {
    openSequence(dir.path());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.item(), "landmark_radius_m");
    EXPECT_NE(e.problem().find("positive"), std::string::npos);
  }
  test::writeFile(dir / "sequence.json", "{ \"beams\": 3,\n oops }");
  try {
    openSequence(dir.path());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(e.item().find("line 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lidarcal::io
