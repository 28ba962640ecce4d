// SPDX-License-Identifier: BSD-3-Clause
// The importers' sink: polar readings to points, --every / --max-scans, sequence.json, and no
// partial output. PCL's own reader is the oracle for the files written.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>

#include "common/errors.hpp"
#include "import_test_util.hpp"
#include "io/sequence.hpp"
#include "io/sequence_writer.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

RawScan polarScan(std::size_t n, double first_rad = 0.0) {
  RawScan s;
  for (std::size_t i = 0; i < n; ++i) {
    s.angles_rad.push_back(first_rad + 2 * kPi * static_cast<double>(i) / static_cast<double>(n));
    s.ranges_m.push_back(1.0f + 0.01f * static_cast<float>(i));
  }
  s.range_min_m = 0.1;
  s.range_max_m = 12.0;
  return s;
}

bool hiddenLeftovers(const std::filesystem::path& dir) {
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().front() == '.') return true;
  return false;
}

TEST(SequenceWriter, PointsAreRangeTimesCosSinOfTheBearingAndPclReadsThem) {
  TempDir dir;
  RawScan s = polarScan(8, -kPi);
  s.pose = Pose2{1.25, -0.5, 0.75};
  s.intensities = {1, 2, 3, 4, 5, 6, 7, 8};
  SequenceWriter w(dir / "seq", {});
  EXPECT_TRUE(w.add(s));
  w.commit("test sensor");
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  ASSERT_EQ(pcl::io::loadPCDFile((dir / "seq/scan_000000.pcd").string(), blob, origin, orientation),
            0);
  bool has_intensity = false;
  for (const auto& f : blob.fields) has_intensity = has_intensity || f.name == "intensity";
  EXPECT_TRUE(has_intensity);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  pcl::fromPCLPointCloud2(blob, cloud);
  ASSERT_EQ(cloud.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) {
    SCOPED_TRACE(i);
    EXPECT_NEAR(test::rangeOf(cloud[i].x, cloud[i].y), s.ranges_m[i], 1e-6);
    EXPECT_NEAR(test::angleDiff(test::bearingOf(cloud[i].x, cloud[i].y), s.angles_rad[i]), 0.0,
                1e-6);
    EXPECT_EQ(cloud[i].z, 0.0f);
    EXPECT_EQ(cloud[i].intensity, s.intensities[i]);
  }
  EXPECT_NEAR(origin[0], 1.25, 1e-6);
  EXPECT_NEAR(origin[1], -0.5, 1e-6);
  EXPECT_NEAR(2 * std::atan2(orientation.z(), orientation.w()), 0.75, 1e-5);
}

TEST(SequenceWriter, NoReturnAndReadingsOutsideTheLimitsBecomeNaNPoints) {
  TempDir dir;
  RawScan s = polarScan(8);
  s.ranges_m = {kNaN, kInf, -kInf, 0.0f, -1.0f, 0.05f, 12.5f, 5.0f};
  SequenceWriter w(dir / "seq", {});
  w.add(s);
  const SequenceWriteSummary sum = w.commit("");
  EXPECT_EQ(sum.no_return, 5u);
  EXPECT_EQ(sum.outside_limits, 2u);
  EXPECT_EQ(sum.returns, 1u);
  const Scan scan = readScan(dir / "seq/scan_000000.pcd");
  ASSERT_EQ(scan.cloud->size(), 8u);
  for (std::size_t i = 0; i < 7; ++i) EXPECT_TRUE(std::isnan((*scan.cloud)[i].x)) << i;
  EXPECT_NEAR(test::rangeOf((*scan.cloud)[7].x, (*scan.cloud)[7].y), 5.0, 1e-6);
  EXPECT_FALSE(scan.has_intensity);
}

TEST(SequenceWriter, EveryAndMaxScansPickScansZeroNTwoN) {
  TempDir dir;
  SequenceWriterConfig c;
  c.every = 3;
  c.max_scans = 3;
  SequenceWriter w(dir / "seq", c);
  std::vector<bool> more;
  for (int k = 0; k < 12; ++k) {
    RawScan s = polarScan(4);
    s.pose.x_m = k;  // identifies the source scan
    more.push_back(w.add(s));
  }
  // Scans 0, 3, 6 are written; add() says "stop" on the third write (source scan 6).
  EXPECT_EQ(more, (std::vector<bool>{true, true, true, true, true, true, false, false, false, false,
                                     false, false}));
  const SequenceWriteSummary sum = w.commit("");
  EXPECT_EQ(sum.written, 3u);
  const Sequence seq = openSequence(dir / "seq");
  ASSERT_EQ(seq.scans.size(), 3u);
  EXPECT_DOUBLE_EQ(seq.scans[0].viewpoint.x_m, 0.0);
  EXPECT_DOUBLE_EQ(seq.scans[1].viewpoint.x_m, 3.0);
  EXPECT_DOUBLE_EQ(seq.scans[2].viewpoint.x_m, 6.0);
}

TEST(SequenceWriter, SequenceJsonHasSensorLimitsAndBeamsOnlyWhenConstant) {
  TempDir dir;
  {
    SequenceWriter w(dir / "same", {});
    w.add(polarScan(360));
    w.add(polarScan(360));
    w.commit("RPLIDAR A2");
  }
  const SequenceMeta same = readSequenceMeta(dir / "same/sequence.json");
  EXPECT_EQ(*same.sensor_name, "RPLIDAR A2");
  EXPECT_EQ(*same.beams, 360);
  EXPECT_DOUBLE_EQ(*same.range_min_m, 0.1);
  EXPECT_DOUBLE_EQ(*same.range_max_m, 12.0);
  {
    SequenceWriter w(dir / "varying", {});
    w.add(polarScan(360));
    RawScan s = polarScan(400);
    s.range_max_m = std::numeric_limits<double>::infinity();
    w.add(s);
    w.commit("");
  }
  const SequenceMeta varying = readSequenceMeta(dir / "varying/sequence.json");
  EXPECT_FALSE(varying.beams);
  EXPECT_FALSE(varying.sensor_name);
  EXPECT_FALSE(varying.range_max_m);  // unbounded: not recorded
}

TEST(SequenceWriter, NothingAppearsWithoutCommit) {
  TempDir dir;
  {
    SequenceWriter w(dir / "seq", {});
    w.add(polarScan(10));
    w.add(polarScan(10));
  }  // e.g. the importer threw
  EXPECT_FALSE(std::filesystem::exists(dir / "seq"));
  EXPECT_FALSE(hiddenLeftovers(dir.path()));
}

TEST(SequenceWriter, RefusesAnExistingOutputAndAnEmptyImport) {
  TempDir dir;
  std::filesystem::create_directories(dir / "taken");
  test::writeFile(dir / "taken/x", "x");
  EXPECT_THROW(SequenceWriter(dir / "taken", {}), InputError);
  SequenceWriter w(dir / "empty", {});
  EXPECT_THROW(w.commit(""), InputError);
  SequenceWriterConfig bad;
  bad.every = 0;
  EXPECT_THROW(SequenceWriter(dir / "bad", bad), InputError);
}

}  // namespace
}  // namespace lidarcal::io
