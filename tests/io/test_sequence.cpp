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
  EXPECT_EQ(stops[0].scans, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(stops[1].scans, (std::vector<std::size_t>{3, 4}));
  EXPECT_EQ(stops[2].scans, (std::vector<std::size_t>{5}));
  EXPECT_EQ(stops[3].scans, (std::vector<std::size_t>{6}));
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
