// SPDX-License-Identifier: BSD-3-Clause
// CSV importer: documented columns, one row per beam, errors naming the line.

#include <cmath>

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "import_test_util.hpp"
#include "io/import_csv.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::Collector;
using test::TempDir;

std::vector<RawScan> read(const TempDir& dir, const std::string& text,
                          const CsvConfig& config = {}) {
  test::writeFile(dir / "scans.csv", text);
  Collector got;
  readCsvScans(dir / "scans.csv", config, got.callback());
  return got.scans;
}

TEST(CsvScans, RowsBecomeScansWithPoseAnglesRangesAndIntensity) {
  TempDir dir;
  const auto scans = read(dir,
                          "# exported by hand\n"
                          "scan,x_m,y_m,yaw_rad,angle_rad,range_m,intensity\n"
                          "0,1.5,-2,0.25,-0.5,1.25,10\n"
                          "0,1.5,-2,0.25,0.0,,11\n"
                          "0,1.5,-2,0.25,0.5,nan,12\n"
                          "\n"
                          "7,1.75,-2,0.5,0.1,3.5,13\n");
  ASSERT_EQ(scans.size(), 2u);
  const RawScan& a = scans[0];
  EXPECT_DOUBLE_EQ(a.pose.x_m, 1.5);
  EXPECT_DOUBLE_EQ(a.pose.y_m, -2.0);
  EXPECT_DOUBLE_EQ(a.pose.yaw_rad, 0.25);
  EXPECT_EQ(a.angles_rad, (std::vector<double>{-0.5, 0.0, 0.5}));
  ASSERT_EQ(a.ranges_m.size(), 3u);
  EXPECT_FLOAT_EQ(a.ranges_m[0], 1.25f);
  EXPECT_TRUE(std::isnan(a.ranges_m[1]));
  EXPECT_TRUE(std::isnan(a.ranges_m[2]));
  EXPECT_EQ(a.intensities, (std::vector<float>{10, 11, 12}));
  EXPECT_DOUBLE_EQ(scans[1].pose.yaw_rad, 0.5);
  EXPECT_EQ(scans[1].ranges_m.size(), 1u);
  EXPECT_EQ(scans[1].source_index, 1u);
}

TEST(CsvScans, ColumnsInAnyOrderAndUnknownColumnsIgnored) {
  TempDir dir;
  const auto scans =
      read(dir, "range_m,comment,angle_rad,yaw_rad,y_m,x_m,scan\n2.0,hello,0.1,0,0,0,3\n");
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[0], 2.0f);
  EXPECT_DOUBLE_EQ(scans[0].angles_rad[0], 0.1);
  EXPECT_TRUE(scans[0].intensities.empty());
}

TEST(CsvScans, RangeLimitsFromTheConfig) {
  TempDir dir;
  CsvConfig c;
  c.range_min_m = 0.2;
  c.range_max_m = 8.0;
  const auto scans = read(dir, "scan,x_m,y_m,yaw_rad,angle_rad,range_m\n0,0,0,0,0,1\n", c);
  EXPECT_DOUBLE_EQ(scans[0].range_min_m, 0.2);
  EXPECT_DOUBLE_EQ(scans[0].range_max_m, 8.0);
  CsvConfig bad;
  bad.range_max_m = 0.0;
  EXPECT_THROW(read(dir, "scan,x_m,y_m,yaw_rad,angle_rad,range_m\n0,0,0,0,0,1\n", bad), InputError);
}

TEST(CsvScans, BadInputNamesTheLine) {
  const std::string head = "scan,x_m,y_m,yaw_rad,angle_rad,range_m\n";
  const std::string row0 = "0,0,0,0,0,1\n";
  for (const auto& [text, expect] : std::vector<std::pair<std::string, std::string>>{
           {"scan,x_m,y_m,yaw_rad,angle_rad\n0,0,0,0,0\n", "line 1 (header): no column 'range_m'"},
           {"scan,x_m,y_m,x_m,yaw_rad,angle_rad,range_m\n", "'x_m' appears twice"},
           {head + row0 + "0,0.1,0,0,0.1,1\n", "line 3: the pose differs from that on line 2"},
           {head + row0 + "1,0,0,0,0,1\n0,0,0,0,0,1\n", "line 4: scan 0 follows scan 1"},
           {head + row0 + "0,0,0,0,0\n", "line 3: has 5 values"},
           {head + row0 + "0,0,0,0,zero,1\n", "line 3: angle_rad is 'zero'"},
           {head + row0 + "0.5,0,0,0,0,1\n", "line 3: scan must be a whole number"},
           {head, "no data row"},
           {"", "no header"}}) {
    SCOPED_TRACE(text);
    TempDir dir;
    try {
      read(dir, text);
      FAIL() << "no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace lidarcal::io
