// SPDX-License-Identifier: BSD-3-Clause
// CARMEN log importer: FLASER and ROBOTLASER1 lines, angle conventions, pose choice, gzip,
// and malformed lines reported with their line number.

#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "common/errors.hpp"
#include "common/pose2.hpp"
#include "import_test_util.hpp"
#include "io/import_carmen.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::Collector;
using test::TempDir;

/// A FLASER line with ranges r_i = 1 + 0.01 i, the laser's pose and the odometry's pose.
std::string flaser(int n, const Pose2& laser, const Pose2& odom, double ts) {
  std::ostringstream o;
  o << "FLASER " << n;
  for (int i = 0; i < n; ++i) o << ' ' << 1.0 + 0.01 * i;
  o << ' ' << laser.x_m << ' ' << laser.y_m << ' ' << laser.yaw_rad << ' ' << odom.x_m << ' '
    << odom.y_m << ' ' << odom.yaw_rad << ' ' << ts << " host " << ts << '\n';
  return o.str();
}

std::string robotlaser1(int n, double start, double res, double max_range, bool remissions) {
  std::ostringstream o;
  o << "ROBOTLASER1 0 " << start << ' ' << res * (n - 1) << ' ' << res << ' ' << max_range
    << " 0.01 0 " << n;
  for (int i = 0; i < n; ++i) o << ' ' << 2.0 + 0.1 * i;
  o << ' ' << (remissions ? n : 0);
  if (remissions)
    for (int i = 0; i < n; ++i) o << ' ' << 100 + i;
  o << " 1.5 2.5 0.3 1.4 2.4 0.2 0 0 0.5 0.2 1000 55.5 host 55.6\n";
  return o.str();
}

std::string header() {
  return "# CARMEN Logfile\n# message formats defined: PARAM SYNC ODOM FLASER RLASER\n"
         "PARAM robot_front_laser_max 50 1.0 host 1.0\nODOM 0 0 0 0 0 0 1.0 host 1.0\n";
}

std::filesystem::path writeLog(const TempDir& dir, const std::string& text,
                               const std::string& name = "log.log") {
  test::writeFile(dir / name, text);
  return dir / name;
}

struct FovCase {
  int beams;
  double first_deg, last_deg;  // CARMEN's table (carmen_laser_get_fov): sweep from -fov/2 to +fov/2
};

void PrintTo(const FovCase& c, std::ostream* os) { *os << c.beams << " beams"; }

class FlaserAngles : public ::testing::TestWithParam<FovCase> {};

TEST_P(FlaserAngles, FollowCarmensFieldOfViewForTheBeamCount) {
  const FovCase c = GetParam();
  TempDir dir;
  Collector got;
  readCarmenLog(writeLog(dir, header() + flaser(c.beams, {}, {}, 1.0)), {}, got.callback());
  ASSERT_EQ(got.scans.size(), 1u);
  const auto& a = got.scans[0].angles_rad;
  ASSERT_EQ(a.size(), static_cast<std::size_t>(c.beams));
  EXPECT_NEAR(a.front(), deg2rad(c.first_deg), 1e-12);
  EXPECT_NEAR(a.back(), deg2rad(c.last_deg), 1e-12);
  const double step = (a.back() - a.front()) / (c.beams - 1);
  for (std::size_t i = 1; i < a.size(); ++i) EXPECT_NEAR(a[i] - a[i - 1], step, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Carmen, FlaserAngles,
                         ::testing::Values(FovCase{181, -90, 90}, FovCase{180, -89.5, 89.5},
                                           FovCase{361, -90, 90}, FovCase{360, -89.75, 89.75},
                                           FovCase{401, -50, 50}, FovCase{400, -49.875, 49.875},
                                           FovCase{90, -90, 90}));

TEST(CarmenLog, FlaserRangesPosesAndTheChoiceOfPose) {
  TempDir dir;
  const auto log = writeLog(dir, header() + flaser(5, {1.5, -2.0, 0.3}, {1.0, -1.0, 0.1}, 10.25) +
                                     "ODOM 1 2 3 0 0 0 10.3 host 10.3\n" +
                                     flaser(5, {1.6, -2.0, 3.5}, {1.1, -1.0, 0.2}, 10.5));
  Collector corrected, odometry;
  const ImportReport r = readCarmenLog(log, {}, corrected.callback());
  CarmenConfig odo;
  odo.pose = CarmenPose::odometry;
  readCarmenLog(log, odo, odometry.callback());
  ASSERT_EQ(r.scans, 2u);
  EXPECT_EQ(r.other_records, 3u);  // PARAM, ODOM, ODOM
  ASSERT_EQ(corrected.scans.size(), 2u);
  const RawScan& s = corrected.scans[0];
  EXPECT_DOUBLE_EQ(s.pose.x_m, 1.5);
  EXPECT_DOUBLE_EQ(s.pose.y_m, -2.0);
  EXPECT_NEAR(s.pose.yaw_rad, 0.3, 1e-12);
  EXPECT_NEAR(corrected.scans[1].pose.yaw_rad, 3.5 - 2 * kPi, 1e-12);  // wrapped
  EXPECT_DOUBLE_EQ(odometry.scans[0].pose.x_m, 1.0);
  EXPECT_DOUBLE_EQ(odometry.scans[0].pose.y_m, -1.0);
  EXPECT_NEAR(odometry.scans[0].pose.yaw_rad, 0.1, 1e-12);
  ASSERT_EQ(s.ranges_m.size(), 5u);
  for (int i = 0; i < 5; ++i)
    EXPECT_FLOAT_EQ(s.ranges_m[static_cast<std::size_t>(i)], static_cast<float>(1.0 + 0.01 * i));
  EXPECT_DOUBLE_EQ(s.stamp_s, 10.25);
  EXPECT_TRUE(s.intensities.empty());
  EXPECT_DOUBLE_EQ(s.range_max_m, kFlaserRangeMax_m);
  EXPECT_EQ(s.source_index, 0u);
  EXPECT_EQ(corrected.scans[1].source_index, 1u);
}

TEST(CarmenLog, RobotLaser1AnglesRemissionsAndMaxRangeComeFromTheLine) {
  TempDir dir;
  const auto log = writeLog(dir, header() + robotlaser1(4, -1.0, 0.25, 30.0, true) +
                                     robotlaser1(4, -1.0, 0.25, 30.0, false));
  Collector got;
  readCarmenLog(log, {}, got.callback());
  ASSERT_EQ(got.scans.size(), 2u);
  const RawScan& s = got.scans[0];
  ASSERT_EQ(s.angles_rad.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(s.angles_rad[i], -1.0 + 0.25 * static_cast<double>(i), 1e-12);
    EXPECT_FLOAT_EQ(s.ranges_m[i], static_cast<float>(2.0 + 0.1 * static_cast<double>(i)));
    EXPECT_FLOAT_EQ(s.intensities[i], static_cast<float>(100 + i));
  }
  EXPECT_DOUBLE_EQ(s.range_max_m, 30.0);
  EXPECT_DOUBLE_EQ(s.pose.x_m, 1.5);  // laser pose
  EXPECT_DOUBLE_EQ(s.stamp_s, 55.5);
  EXPECT_TRUE(got.scans[1].intensities.empty());
  CarmenConfig odo;
  odo.pose = CarmenPose::odometry;
  odo.range_max_m = 20.0;
  Collector robot;
  readCarmenLog(log, odo, robot.callback());
  EXPECT_DOUBLE_EQ(robot.scans[0].pose.x_m, 1.4);  // robot pose
  EXPECT_NEAR(robot.scans[0].pose.yaw_rad, 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(robot.scans[0].range_max_m, 20.0);
}

TEST(CarmenLog, TheFirstLaserKindWinsAndTheOtherIsIgnored) {
  TempDir dir;
  const auto log = writeLog(dir, header() + flaser(3, {}, {}, 1) +
                                     robotlaser1(4, -1, 0.25, 30, false) + flaser(3, {}, {}, 2));
  Collector got;
  const ImportReport r = readCarmenLog(log, {}, got.callback());
  EXPECT_EQ(r.scans, 2u);
  EXPECT_EQ(r.other_records, 3u);
  EXPECT_EQ(r.sensor_name, "CARMEN front laser (FLASER)");
}

TEST(CarmenLog, GzipAndPlainGiveTheSameScans) {
  TempDir dir;
  std::string text = header();
  for (int k = 0; k < 50; ++k) text += flaser(181, {0.1 * k, 0.2, 0.01 * k}, {}, k);
  Collector plain, gz;
  readCarmenLog(writeLog(dir, text), {}, plain.callback());
  test::writeGzip(dir / "log.log.gz", text);
  readCarmenLog(dir / "log.log.gz", {}, gz.callback());
  ASSERT_EQ(plain.scans.size(), 50u);
  ASSERT_EQ(gz.scans.size(), 50u);
  for (std::size_t k = 0; k < 50; ++k) {
    EXPECT_EQ(plain.scans[k].ranges_m, gz.scans[k].ranges_m);
    EXPECT_EQ(plain.scans[k].pose.x_m, gz.scans[k].pose.x_m);
  }
}

TEST(CarmenLog, StopsWhenTheCallbackSaysSo) {
  TempDir dir;
  std::string text = header();
  for (int k = 0; k < 10; ++k) text += flaser(3, {}, {}, k);
  Collector got;
  got.stop_after = 4;
  const ImportReport r = readCarmenLog(writeLog(dir, text), {}, got.callback());
  EXPECT_EQ(r.scans, 4u);
  EXPECT_TRUE(r.stopped_early);
}

struct BadLine {
  const char* name;
  std::string line;    // placed on line 6 of the log (after 4 header lines and one good laser line)
  const char* expect;  // must appear in the message
  bool robotlaser = false;  // the good lines are ROBOTLASER1 (else FLASER)
};

void PrintTo(const BadLine& c, std::ostream* os) { *os << c.name; }

class CarmenBadLine : public ::testing::TestWithParam<BadLine> {};

TEST_P(CarmenBadLine, IsAnErrorNamingTheLine) {
  const BadLine& c = GetParam();
  TempDir dir;
  const std::string good =
      c.robotlaser ? robotlaser1(4, -1, 0.25, 30, false) : flaser(3, {}, {}, 1);
  const auto log = writeLog(dir, header() + good + c.line + good);
  Collector got;
  try {
    readCarmenLog(log, {}, got.callback());
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(log.string()), std::string::npos) << what;
    EXPECT_NE(what.find("line 6"), std::string::npos) << what;
    EXPECT_NE(what.find(c.expect), std::string::npos) << what;
    EXPECT_FALSE(e.remedy().empty());
  }
}

std::string withoutLastValue(std::string line) {
  line.pop_back();  // '\n'
  line.erase(line.rfind(' '));
  return line + "\n";
}

INSTANTIATE_TEST_SUITE_P(
    Carmen, CarmenBadLine,
    ::testing::Values(
        BadLine{"OneValueShort", withoutLastValue(flaser(3, {}, {}, 1)),
                "has 12 values after FLASER, expected 13"},
        BadLine{"OneValueTooMany", "FLASER 2 1.0 1.1 1.2 0 0 0 0 0 0 1 host 1\n", "expected 12"},
        BadLine{"CountSaysMore", "FLASER 4 1.0 1.1 0 0 0 0 0 0 1 host 1\n", "expected 14"},
        BadLine{"RangeNotANumber", "FLASER 2 1.0 abc 0 0 0 0 0 0 1 host 1\n",
                "'abc', not a number"},
        BadLine{"NoCount", "FLASER\n", "beam count"},
        BadLine{"NegativeCount", "FLASER -3 1 2 3\n", "whole number"},
        BadLine{"PoseNotFinite", "FLASER 2 1.0 1.1 nan 0 0 0 0 0 1 host 1\n", "pose is not finite"},
        BadLine{"RobotLaserShort", withoutLastValue(robotlaser1(4, -1, 0.25, 30, false)),
                "line 6 (ROBOTLASER1): has 26 values after ROBOTLASER1, expected 27", true}),
    [](const auto& p) { return std::string(p.param.name); });

TEST(CarmenLog, NoLaserLineIsAnError) {
  TempDir dir;
  Collector got;
  EXPECT_THROW(readCarmenLog(writeLog(dir, header()), {}, got.callback()), InputError);
}

TEST(CarmenLog, DamagedGzipIsAnErrorNamingTheFile) {
  TempDir dir;
  std::string text = header();
  for (int k = 0; k < 400; ++k) text += flaser(361, {0.1 * k, 0.2, 0.01 * k}, {}, k);
  test::writeGzip(dir / "good.log.gz", text);
  const std::string gz = test::readFile(dir / "good.log.gz");
  test::writeFile(dir / "cut.log.gz", gz.substr(0, gz.size() / 2));
  std::string flipped = gz;
  for (std::size_t i = gz.size() / 3; i < gz.size() / 3 + 64; ++i)
    flipped[i] = static_cast<char>(~flipped[i]);
  test::writeFile(dir / "flipped.log.gz", flipped);
  for (const char* name : {"cut.log.gz", "flipped.log.gz"}) {
    SCOPED_TRACE(name);
    Collector got;
    try {
      readCarmenLog(dir / name, {}, got.callback());
      FAIL() << "no error";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(name), std::string::npos) << what;
      EXPECT_NE(what.find("line"), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace lidarcal::io
