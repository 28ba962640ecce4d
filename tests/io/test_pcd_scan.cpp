// SPDX-License-Identifier: BSD-3-Clause
// PCD scan files: round trips, interoperability with PCL's own reader, and bad input.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>

#include "common/errors.hpp"
#include "io/pcd_scan.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;

Scan makeScan(std::size_t n, bool intensity, bool labels) {
  Scan s;
  s.name = "t.pcd";
  s.viewpoint = Pose2{1.25, -0.5, 0.7};
  s.has_intensity = intensity;
  s.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  s.cloud->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    auto& p = (*s.cloud)[i];
    const double a = 0.1 * static_cast<double>(i);
    if (i % 7 == 3) {  // beams without return keep their place
      p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
    } else {
      p.x = static_cast<float>(std::cos(a) * (1.0 + 0.01 * static_cast<double>(i)));
      p.y = static_cast<float>(std::sin(a) * 1.0 / 3.0);
      p.z = 0.0f;
    }
    p.intensity = intensity ? static_cast<float>(i) * 0.5f : 0.0f;
    if (labels) s.labels.push_back(static_cast<std::uint32_t>(i % 4));
  }
  return s;
}

class PcdRoundTrip : public ::testing::TestWithParam<PcdEncoding> {};

TEST_P(PcdRoundTrip, KeepsEveryPointNaNOrderViewpointIntensityAndLabel) {
  TempDir dir;
  const Scan in = makeScan(50, true, true);
  writeScan(dir / "t.pcd", in, GetParam());
  const Scan out = readScan(dir / "t.pcd");
  ASSERT_EQ(out.cloud->size(), in.cloud->size());
  EXPECT_TRUE(out.has_intensity);
  ASSERT_EQ(out.labels, in.labels);
  for (std::size_t i = 0; i < in.cloud->size(); ++i) {
    SCOPED_TRACE(i);
    const auto& a = (*in.cloud)[i];
    const auto& b = (*out.cloud)[i];
    if (std::isnan(a.x)) {
      EXPECT_TRUE(std::isnan(b.x) && std::isnan(b.y));
      continue;
    }
    EXPECT_EQ(a.x, b.x);  // 9 significant digits in ASCII are exact for float
    EXPECT_EQ(a.y, b.y);
    EXPECT_EQ(a.intensity, b.intensity);
  }
  EXPECT_NEAR(out.viewpoint.x_m, 1.25, 1e-5);
  EXPECT_NEAR(out.viewpoint.y_m, -0.5, 1e-5);
  EXPECT_NEAR(out.viewpoint.yaw_rad, 0.7, 1e-5);
}

TEST_P(PcdRoundTrip, OptionalFieldsStayAbsent) {
  TempDir dir;
  writeScan(dir / "t.pcd", makeScan(10, false, false), GetParam());
  const Scan out = readScan(dir / "t.pcd");
  EXPECT_FALSE(out.has_intensity);
  EXPECT_TRUE(out.labels.empty());
}

INSTANTIATE_TEST_SUITE_P(Encodings, PcdRoundTrip,
                         ::testing::Values(PcdEncoding::binary, PcdEncoding::ascii));

TEST(PcdScan, PclsOwnReaderOpensOurFilesWithTheViewpoint) {
  TempDir dir;
  Scan in = makeScan(20, false, true);
  in.viewpoint = Pose2{-2.0, 3.5, -2.5};
  writeScan(dir / "t.pcd", in);
  pcl::PointCloud<pcl::PointXYZL> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile((dir / "t.pcd").string(), cloud), 0);
  ASSERT_EQ(cloud.size(), 20u);
  EXPECT_NEAR(cloud.sensor_origin_[0], -2.0, 1e-5);
  EXPECT_NEAR(cloud.sensor_origin_[1], 3.5, 1e-5);
  const auto& q = cloud.sensor_orientation_;
  EXPECT_NEAR(2.0 * std::atan2(q.z(), q.w()), -2.5, 1e-5);
  EXPECT_EQ(cloud[5].label, 1u);
  EXPECT_TRUE(std::isnan(cloud[3].x));
}

TEST(PcdScan, ReadsFilesWrittenByPcl) {
  TempDir dir;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(1.0f, 2.0f, 0.0f));
  cloud.push_back(pcl::PointXYZ(std::numeric_limits<float>::quiet_NaN(),
                                std::numeric_limits<float>::quiet_NaN(),
                                std::numeric_limits<float>::quiet_NaN()));
  cloud.is_dense = false;
  cloud.sensor_origin_ = Eigen::Vector4f(0.5f, 0.25f, 0.0f, 0.0f);
  cloud.sensor_orientation_ = Eigen::Quaternionf(std::cos(0.2f), 0.0f, 0.0f, std::sin(0.2f));
  pcl::io::savePCDFileASCII((dir / "a.pcd").string(), cloud);
  pcl::io::savePCDFileBinaryCompressed((dir / "c.pcd").string(), cloud);
  for (const char* name : {"a.pcd", "c.pcd"}) {
    SCOPED_TRACE(name);
    const Scan s = readScan(dir / name);
    ASSERT_EQ(s.cloud->size(), 2u);
    EXPECT_FLOAT_EQ((*s.cloud)[0].y, 2.0f);
    EXPECT_TRUE(std::isnan((*s.cloud)[1].x));
    EXPECT_NEAR(s.viewpoint.yaw_rad, 0.4, 1e-5);
    EXPECT_NEAR(s.viewpoint.x_m, 0.5, 1e-6);
  }
}

// ---- bad input: each case names the file and the item, and says what is wrong ----

struct BadPcdCase {
  const char* name;
  std::string content;
  const char* expected_item;
  const char* expected_problem;
};

/// A PCD header; by default one x y z float point in ascii, the case each bad file departs from.
struct PcdHeader {
  std::string fields = "x y z";
  std::string sizes = "4 4 4";
  std::string types = "F F F";
  int points = 1;
  std::string viewpoint = "VIEWPOINT 0 0 0 1 0 0 0\n";  ///< the whole line; "" for none
  std::string data = "ascii";
  int width = -1;  ///< -1: as many as points
};

std::string header(const PcdHeader& h) {
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS " + h.fields + "\nSIZE " + h.sizes + "\nTYPE " +
         h.types + "\nCOUNT 1 1 1\nWIDTH " + std::to_string(h.width < 0 ? h.points : h.width) +
         "\nHEIGHT 1\n" + h.viewpoint + "POINTS " + std::to_string(h.points) + "\nDATA " + h.data +
         "\n";
}

/// The default header for `points` points with the one departure `edit` makes.
template <typename Edit>
std::string header(int points, Edit edit) {
  PcdHeader h;
  h.points = points;
  edit(h);
  return header(h);
}

std::string header(int points) {
  return header(points, [](PcdHeader&) {});
}

class BadPcd : public ::testing::TestWithParam<BadPcdCase> {};

TEST_P(BadPcd, GivesAClearError) {
  TempDir dir;
  const auto file = dir / "bad.pcd";
  test::writeFile(file, GetParam().content);
  try {
    readScan(file);
    FAIL() << "no error for " << GetParam().name;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file.string());
    EXPECT_NE(e.item().find(GetParam().expected_item), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(GetParam().expected_problem), std::string::npos)
        << e.what();
  }
}

std::string truncatedBinary() {
  return header(100, [](PcdHeader& h) { h.data = "binary"; }) + std::string(100 * 12 - 5, '\0');
}

INSTANTIATE_TEST_SUITE_P(
    Catalogue, BadPcd,
    ::testing::Values(
        BadPcdCase{"garbage",
                   "\x7f"
                   "ELF garbage\x01\x02\n",
                   "header line 1", "unknown header keyword"},
        BadPcdCase{"empty", "", "DATA", "no DATA line"},
        BadPcdCase{"truncated binary", truncatedBinary(), "DATA", "truncated"},
        BadPcdCase{"truncated ascii", header(3) + "1 2 0\n", "DATA", "truncated"},
        BadPcdCase{"no x", header(1, [](PcdHeader& h) { h.fields = "a y z"; }) + "1 2 0\n",
                   "FIELDS", "no 'x' field"},
        BadPcdCase{"no y", header(1, [](PcdHeader& h) { h.fields = "x b z"; }) + "1 2 0\n",
                   "FIELDS", "no 'y' field"},
        BadPcdCase{"points != width*height",
                   header(3, [](PcdHeader& h) { h.width = 2; }) + "1 2 0\n1 2 0\n1 2 0\n", "POINTS",
                   "differs from WIDTH x HEIGHT"},
        BadPcdCase{"missing viewpoint",
                   header(1, [](PcdHeader& h) { h.viewpoint = ""; }) + "1 2 0\n", "VIEWPOINT",
                   "missing"},
        BadPcdCase{"short viewpoint",
                   header(1, [](PcdHeader& h) { h.viewpoint = "VIEWPOINT 0 0 0 1\n"; }) + "1 2 0\n",
                   "VIEWPOINT", "expected 7 numbers"},
        BadPcdCase{
            "non-unit quaternion",
            header(1, [](PcdHeader& h) { h.viewpoint = "VIEWPOINT 0 0 0 2 0 0 0\n"; }) + "1 2 0\n",
            "VIEWPOINT", "unit length"},
        BadPcdCase{
            "roll in viewpoint",
            header(1, [](PcdHeader& h) { h.viewpoint = "VIEWPOINT 0 0 0 0.7071 0.7071 0 0\n"; }) +
                "1 2 0\n",
            "VIEWPOINT", "only a yaw rotation"},
        BadPcdCase{"infinite coordinate", header(1) + "inf 2 0\n", "point 0", "infinite"},
        BadPcdCase{"absurd range", header(1) + "1e30 2 0\n", "point 0", "beyond 100 km"},
        BadPcdCase{"half NaN", header(1) + "nan 2 0\n", "point 0", "only one of x, y is NaN"},
        BadPcdCase{"integer x", header(1, [](PcdHeader& h) { h.types = "I F F"; }) + "1 2 0\n",
                   "field 'x'", "single float"}),
    [](const ::testing::TestParamInfo<BadPcdCase>& p) {
      std::string n = p.param.name;
      for (char& c : n)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return n;
    });

TEST(PcdScan, MissingFileIsReported) {
  try {
    readScan("/nonexistent/x.pcd");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
  }
}

}  // namespace
}  // namespace lidarcal::io
