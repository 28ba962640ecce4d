// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal odometry-drive` end to end on the bundled drive (data/drive, drawn by
// `bench/drive_bound --write-example` from the default simulated drive, whose truth the test
// takes from DriveSimulation): the table and OUT.json, held parameters, what the data cannot
// separate, and bad input.

#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "odometry/simulated_drive.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;

std::string inputs(const std::filesystem::path& dir = test::sourceDir() / "data/drive") {
  return "odometry-drive --wheels " + (dir / "wheel_angles.csv").string() + " --landmarks " +
         (dir / "landmarks.csv").string() + " --nominal 0.05,0.05,0.30,0.10,0,0";
}

TEST(CliOdometryDrive, CalibratesTheBundledDriveWithinItsStandardErrors) {
  TempDir dir;
  const auto r = runCli(inputs() + " -o " + (dir / "out.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| range offset a_0 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| range scale a_1 | 0.000 | held | % |"), std::string::npos) << r.out;
  const nlohmann::json j = nlohmann::json::parse(test::readFile(dir / "out.json"));
  EXPECT_EQ(j["format"], "lidarcal-odometry-drive/1");
  EXPECT_EQ(j["status"]["code"], "ok");
  EXPECT_TRUE(j["standard_error"]["range_scale"].is_null());
  const odometry::Vector8 truth = odometry::DriveSimulation{}.truth.toVector();
  for (int i = 0; i < 7; ++i) {
    const char* name = odometry::kDriveParameterNames[i];
    const double se = j["standard_error"][name].get<double>();
    EXPECT_GT(se, 0.0) << name;
    EXPECT_LT(std::abs(j["estimate"][name].get<double>() - truth[i]), 4.0 * se) << name;
  }
  // The bundled drive's noise is the defaults': each variance factor is near 1 within 4 of its
  // standard deviations, sqrt(2 / redundancy); the redundancies sum to the degrees of freedom.
  double dof = 0.0;
  for (const char* kind : {"odometry_translation", "odometry_heading", "range", "bearing"}) {
    const double redundancy = j["by_kind"][kind]["redundancy"].get<double>();
    dof += redundancy;
    EXPECT_GT(redundancy, 10.0) << kind;
    EXPECT_NEAR(j["by_kind"][kind]["variance_factor"].get<double>(), 1.0,
                4.0 * std::sqrt(2.0 / redundancy))
        << kind;
  }
  const double free = 3.0 * 898 + 2.0 * 6 + 7;  // poses after the first, poles, estimated
  EXPECT_NEAR(dof, 3.0 * 898 + 2.0 * 5394 - free, 1e-6);
  EXPECT_NEAR(j["variance_factor"].get<double>(), 1.0, 4.0 * std::sqrt(2.0 / dof));
}

TEST(CliOdometryDrive, MisstatedNoiseShowsInTheFactorAndTheStandardErrors) {
  // The range noise stated 4 times too small: its variance factor is near 16, the bearing's near
  // 1, and the standard errors follow the data rather than the statement.
  TempDir dir;
  const auto r = runCli(inputs() + " --range-sigma 0.0025 -o " + (dir / "out.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(test::readFile(dir / "out.json"));
  EXPECT_GT(j["by_kind"]["range"]["variance_factor"].get<double>(), 10.0);
  EXPECT_LT(j["by_kind"]["bearing"]["variance_factor"].get<double>(), 1.5);
  EXPECT_GT(j["variance_factor"].get<double>(), 2.0);
  const double scaled = j["standard_error"]["range_offset_m"].get<double>();
  const double stated = j["standard_error_stated_noise"]["range_offset_m"].get<double>();
  EXPECT_NEAR(scaled / stated, std::sqrt(j["variance_factor"].get<double>()), 1e-9);
}

TEST(CliOdometryDrive, HeldParametersStayAtTheirNominalValue) {
  TempDir dir;
  const auto r =
      runCli(inputs() + " --hold range_offset_m,laser_y_m -o " + (dir / "out.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(test::readFile(dir / "out.json"));
  EXPECT_EQ(j["estimate"]["range_offset_m"].get<double>(), 0.0);
  EXPECT_EQ(j["estimate"]["laser_y_m"].get<double>(), 0.0);
  EXPECT_TRUE(j["standard_error"]["laser_y_m"].is_null());
  EXPECT_EQ(j["held"].size(), 3u) << j["held"].dump();
}

TEST(CliOdometryDrive, SaysWhatTheDriveCannotSeparate) {
  TempDir dir;
  const auto r = runCli(inputs() + " --estimate-range-scale -o " + (dir / "out.json").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("undetermined:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("range_scale"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("left_radius_m"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.json"));
}

TEST(CliOdometryDrive, ASightingOfAScanWithoutWheelAnglesIsNamed) {
  TempDir dir;
  const std::filesystem::path example = test::sourceDir() / "data/drive";
  test::writeFile(
      dir / "wheel_angles.csv",
      "file,left_wheel_rad,right_wheel_rad\nscan_000000.pcd,0,0\nscan_000001.pcd,0.6,0.6\n");
  std::filesystem::copy_file(example / "landmarks.csv", dir / "landmarks.csv");
  const auto r = runCli(inputs(dir.path()) + " -o " + (dir / "out.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("landmarks.csv"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("scan_000002.pcd"), std::string::npos) << r.err;
}

TEST(CliOdometryDrive, AWheelAngleThatIsNotANumberIsNamed) {
  TempDir dir;
  test::writeFile(
      dir / "wheel_angles.csv",
      "file,left_wheel_rad,right_wheel_rad\nscan_000000.pcd,0,0\nscan_000001.pcd,x,0.6\n");
  test::writeFile(dir / "landmarks.csv", "");
  const auto r = runCli(inputs(dir.path()) + " -o " + (dir / "out.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("wheel_angles.csv"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("left_wheel_rad"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace lidarcal
