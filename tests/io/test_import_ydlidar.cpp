// SPDX-License-Identifier: BSD-3-Clause
// YDLIDAR X4 dataset importer: odometry integration (closed forms), beam angles, first-line
// deltas, malformed lines.

#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "import_test_util.hpp"
#include "io/import_ydlidar.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::Collector;
using test::TempDir;

/// One .dat line: distance (mm), dtheta (deg), dt (s), then `n` ranges r_i = 1 + 0.001 i.
std::string datLine(double dist_mm, double dtheta_deg, double dt, int n) {
  std::ostringstream o;
  o.precision(17);
  o << dist_mm << ", " << dtheta_deg << ", " << dt;
  for (int i = 0; i < n; ++i) o << ", " << (i % 3 == 0 ? 0.0 : 1.0 + 0.001 * i);
  o << '\n';
  return o.str();
}

std::vector<RawScan> read(const TempDir& dir, const std::string& text,
                          const YdlidarConfig& config = {}) {
  test::writeFile(dir / "rec.dat", text);
  Collector got;
  readYdlidarDat(dir / "rec.dat", config, got.callback());
  return got.scans;
}

TEST(YdlidarIntegration, StraightStepsAndTurnsInPlaceAreExact) {
  const Pose2 a = integrateOdometry(Pose2{1, 2, 0.5}, 0.0, 0.25);
  EXPECT_DOUBLE_EQ(a.x_m, 1.0);
  EXPECT_DOUBLE_EQ(a.y_m, 2.0);
  EXPECT_DOUBLE_EQ(a.yaw_rad, 0.75);
  const Pose2 b = integrateOdometry(Pose2{1, 2, kPi / 2}, 0.5, 0.0);
  EXPECT_NEAR(b.x_m, 1.0, 1e-15);
  EXPECT_NEAR(b.y_m, 2.5, 1e-15);
}

TEST(YdlidarIntegration, ChordsOfARegularPolygonCloseTheLoop) {
  // N chords of length c, turning 2 pi / N each: the midpoint heading makes every step a chord
  // of one circle, so the path returns exactly to the start (a regular N-gon).
  for (int n : {3, 4, 7, 36}) {
    SCOPED_TRACE(n);
    Pose2 p{0.3, -0.2, 0.1};
    for (int k = 0; k < n; ++k) p = integrateOdometry(p, 0.5, 2 * kPi / n);
    EXPECT_NEAR(p.x_m, 0.3, 1e-12);
    EXPECT_NEAR(p.y_m, -0.2, 1e-12);
    EXPECT_NEAR(std::abs(wrapAngle(p.yaw_rad - 0.1)), 0.0, 1e-12);
  }
}

TEST(YdlidarDat, PosesFromMillimetresAndDegreesFirstLineDeltasNotApplied) {
  TempDir dir;
  // Line 1 carries motion from before the recording (ignored). Then a 1 m square,
  // counter-clockwise.
  std::string text = datLine(1234, -754.3, 89.2, 8);
  for (int side = 0; side < 4; ++side) text += datLine(1000, 0, 0.1, 8) + datLine(0, 90, 0.1, 8);
  const auto scans = read(dir, text);
  ASSERT_EQ(scans.size(), 9u);
  const double expected[9][3] = {{0, 0, 0},   {1, 0, 0},   {1, 0, 90},  {1, 1, 90}, {1, 1, 180},
                                 {0, 1, 180}, {0, 1, -90}, {0, 0, -90}, {0, 0, 0}};
  for (std::size_t k = 0; k < 9; ++k) {
    SCOPED_TRACE(k);
    EXPECT_NEAR(scans[k].pose.x_m, expected[k][0], 1e-12);
    EXPECT_NEAR(scans[k].pose.y_m, expected[k][1], 1e-12);
    EXPECT_NEAR(std::abs(wrapAngle(scans[k].pose.yaw_rad - deg2rad(expected[k][2]))), 0.0, 1e-12);
    EXPECT_NEAR(scans[k].stamp_s, 0.1 * static_cast<double>(k), 1e-12);
  }
}

TEST(YdlidarDat, BeamIAtTwoPiIOverNRangesAsWrittenLimitsFromTheDatasetReadme) {
  TempDir dir;
  const auto scans = read(dir, datLine(0, 0, 0, 640) + datLine(0, 0, 0.1, 7));
  ASSERT_EQ(scans.size(), 2u);
  for (const auto& s : scans) {
    const std::size_t n = s.ranges_m.size();
    ASSERT_EQ(s.angles_rad.size(), n);
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_NEAR(s.angles_rad[i], 2 * kPi * static_cast<double>(i) / static_cast<double>(n),
                  1e-12);
      EXPECT_FLOAT_EQ(s.ranges_m[i],
                      i % 3 == 0 ? 0.0f : static_cast<float>(1.0 + 0.001 * static_cast<double>(i)));
    }
    EXPECT_DOUBLE_EQ(s.range_min_m, 0.12);
    EXPECT_DOUBLE_EQ(s.range_max_m, 10.0);
  }
  EXPECT_EQ(scans[0].ranges_m.size(), 640u);
  EXPECT_EQ(scans[1].ranges_m.size(), 7u);
}

TEST(YdlidarDat, GzipIsReadToo) {
  TempDir dir;
  const std::string text = datLine(0, 0, 0, 10) + datLine(100, 10, 0.1, 10);
  test::writeGzip(dir / "rec.dat.gz", text);
  Collector got;
  readYdlidarDat(dir / "rec.dat.gz", {}, got.callback());
  ASSERT_EQ(got.scans.size(), 2u);
  EXPECT_NEAR(got.scans[1].pose.x_m, 0.1 * std::cos(deg2rad(5)), 1e-12);
}

TEST(YdlidarDat, MalformedLinesNameTheLine) {
  TempDir dir;
  const std::string good = datLine(0, 0, 0, 5);
  for (const auto& [bad, expect] : std::vector<std::pair<std::string, std::string>>{
           {"1, 2, 3\n", "at least one range"},
           {"1, x, 3, 1.0\n", "dtheta is 'x'"},
           {"1, 2, 3, 1.0, , 2.0\n", "range 1 is ''"},
           {"1, 2, 3, 1.0, 2.0e\n", "range 1 is '2.0e'"}}) {
    SCOPED_TRACE(bad);
    try {
      read(dir, good + good + bad);
      FAIL() << "no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(read(dir, "\n\n"), InputError);  // no scan at all
}

}  // namespace
}  // namespace lidarcal::io
