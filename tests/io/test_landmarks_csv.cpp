// SPDX-License-Identifier: BSD-3-Clause
// landmarks.csv: round trip, quoting, and errors that name the line and column.

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "io/landmarks_csv.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;

TEST(LandmarksCsv, RoundTripKeepsEveryFieldAndQuotesOddFileNames) {
  TempDir dir;
  const std::vector<LandmarkRow> rows = {
      {"scan_000000.pcd", 0, 1, -3.1, 2.5, -2.4, -0.1, 0.12, 7, 0.0012345678},
      {"odd, \"name\".pcd", 12, 42, 3.14159, 0.5, 0.0, 0.5, 0.05, 3, 0.0}};
  {
    LandmarksCsvWriter w(dir / "landmarks.csv");
    for (const auto& r : rows) w.write(r);
    w.close();
  }
  const std::string text = test::readFile(dir / "landmarks.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')), landmarksCsvHeader());
  const auto back = readLandmarksCsv(dir / "landmarks.csv");
  ASSERT_EQ(back.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(back[i].file, rows[i].file);
    EXPECT_EQ(back[i].stop, rows[i].stop);
    EXPECT_EQ(back[i].landmark, rows[i].landmark);
    EXPECT_NEAR(back[i].bearing_rad, rows[i].bearing_rad, 1e-9);
    EXPECT_NEAR(back[i].range_m, rows[i].range_m, 1e-9);
    EXPECT_NEAR(back[i].centre_x_m, rows[i].centre_x_m, 1e-9);
    EXPECT_NEAR(back[i].centre_y_m, rows[i].centre_y_m, 1e-9);
    EXPECT_NEAR(back[i].radius_m, rows[i].radius_m, 1e-9);
    EXPECT_EQ(back[i].n_points, rows[i].n_points);
    EXPECT_NEAR(back[i].rms_m, rows[i].rms_m, 1e-9);
  }
}

TEST(LandmarksCsv, BadContentNamesTheLineAndColumn) {
  TempDir dir;
  const std::string header = std::string(landmarksCsvHeader()) + "\n";
  struct Case {
    std::string body, expect;
  };
  for (const Case& c : {Case{"a.pcd,0,1,0.1,2,1,1,0.1,5\n", "line 3"},
                        Case{"a.pcd,0,1,0.1,abc,1,1,0.1,5,0.01\n", "column range_m"},
                        Case{"a.pcd,0,0,0.1,2,1,1,0.1,5,0.01\n", "column landmark"},
                        Case{"a.pcd,-1,1,0.1,2,1,1,0.1,5,0.01\n", "column stop"},
                        Case{"a.pcd,0,1,0.1,2,1,1,0.1,5.5,0.01\n", "column n_points"},
                        Case{"\"a.pcd,0,1,0.1,2,1,1,0.1,5,0.01\n", "quotes"},
                        Case{"a.pcd,0,1,0.1,nan,1,1,0.1,5,0.01\n", "column range_m"}}) {
    SCOPED_TRACE(c.body);
    test::writeFile(dir / "l.csv", header + "a.pcd,0,1,0.1,2,1,1,0.1,5,0.01\n" + c.body);
    try {
      readLandmarksCsv(dir / "l.csv");
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
    }
  }
  test::writeFile(dir / "h.csv", "file,stop\n");
  EXPECT_THROW(readLandmarksCsv(dir / "h.csv"), InputError);
  EXPECT_THROW(readLandmarksCsv(dir / "missing.csv"), InputError);
}

}  // namespace
}  // namespace lidarcal::io
