// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal odometry-drive` end to end on the bundled drive (data/drive, drawn by
// `bench/drive_bound --write-example` from the default simulated drive, whose truth the test
// takes from DriveSimulation): the table and OUT.json, held parameters, what the data cannot
// separate, and bad input.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/pose2.hpp"
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

/// The wheels' cumulative angles at each pose of truth.json for wheels of radius 50 mm on a
/// 300 mm axle: each true step as the arc the two wheels drive.
std::string wheelAnglesOf(const nlohmann::json& truth) {
  constexpr double kRadius = 0.05, kAxle = 0.30;
  std::string csv = "file,left_wheel_rad,right_wheel_rad\n";
  double left = 0.0, right = 0.0;
  const nlohmann::json* prev = nullptr;
  char row[128];
  for (const nlohmann::json& stop : truth["stops"]) {
    const nlohmann::json& a = stop["actual"];
    if (prev != nullptr) {
      const double yaw = (*prev)["yaw_rad"].get<double>();
      const double dx = a["x_m"].get<double>() - (*prev)["x_m"].get<double>();
      const double dy = a["y_m"].get<double>() - (*prev)["y_m"].get<double>();
      const double turn = std::remainder(a["yaw_rad"].get<double>() - yaw, 2.0 * kPi);
      const double chord = std::hypot(dx, dy);
      double distance = std::abs(turn) < 1e-12 ? chord : chord * (turn / 2) / std::sin(turn / 2);
      if (std::cos(yaw) * dx + std::sin(yaw) * dy < 0.0) distance = -distance;
      left += (distance - turn * kAxle / 2) / kRadius;
      right += (distance + turn * kAxle / 2) / kRadius;
    }
    std::snprintf(row, sizeof row, "scan_%06d.pcd,%.12g,%.12g\n", stop["first_scan"].get<int>(),
                  left, right);
    csv += row;
    prev = &a;
  }
  return csv;
}

TEST(CliOdometryDrive, BeamsTakeOutTheErrorOfCirclesThroughBiasedReturns) {
  // The bundled driving scene with a laser that reads 30 mm long, no noise and exact odometry,
  // simulated and detected with the poles' known radius. Each return moved 30 mm along its own
  // beam, so a circle of the known radius through them sits short of 30 mm; beam by beam the
  // fit explains the returns as they were made.
  TempDir dir;
  nlohmann::json scene = nlohmann::json::parse(
      test::readFile(test::sourceDir() / "data/scenes/driving_large_poles.json"));
  scene["sensor"]["bias_alpha"] = {0.03, 1.0};
  scene["sensor"]["noise"] = {{"kind", "none"}};
  scene["path"]["odometry"] = {
      {"translation_fraction", 0.0}, {"heading_deg_per_m", 0.0}, {"heading_fraction", 0.0}};
  scene["clutter"] = nlohmann::json::array();
  test::writeFile(dir / "scene.json", scene.dump());
  ASSERT_EQ(runCli("--quiet simulate --scene " + (dir / "scene.json").string() + " -o " +
                   (dir / "sim").string() + " --seed 1")
                .exit_code,
            0);
  ASSERT_EQ(runCli("--quiet detect " + (dir / "sim/scans").string() + " --out " +
                   (dir / "det").string() + " --radius 0.1")
                .exit_code,
            0);
  test::writeFile(dir / "wheels.csv",
                  wheelAnglesOf(nlohmann::json::parse(test::readFile(dir / "sim/truth.json"))));
  const std::string fit = "--quiet odometry-drive --wheels " + (dir / "wheels.csv").string() +
                          " --landmarks " + (dir / "det/landmarks.csv").string() +
                          " --nominal 0.05,0.05,0.30,0,0,0 -o ";
  const auto circles = runCli(fit + (dir / "circles.json").string());
  const auto beams = runCli(fit + (dir / "beams.json").string() + " --beams");
  ASSERT_EQ(circles.exit_code, 0) << circles.err;
  ASSERT_EQ(beams.exit_code, 0) << beams.err;
  EXPECT_NE(beams.out.find(" beams on "), std::string::npos) << beams.out;
  const nlohmann::json c = nlohmann::json::parse(test::readFile(dir / "circles.json"));
  const nlohmann::json b = nlohmann::json::parse(test::readFile(dir / "beams.json"));
  EXPECT_GT(std::abs(c["estimate"]["range_offset_m"].get<double>() - 0.03), 5e-4)
      << "circles through the biased returns fall short of the offset";
  EXPECT_NEAR(b["estimate"]["range_offset_m"].get<double>(), 0.03, 1e-4);
  EXPECT_GT(b["drive"]["beams"].get<int>(), 2 * b["drive"]["sightings"].get<int>());
  for (const char* name : {"left_radius_m", "right_radius_m"})
    EXPECT_NEAR(b["estimate"][name].get<double>(), 0.05, 5e-5) << name;
  EXPECT_NEAR(b["estimate"]["axle_m"].get<double>(), 0.30, 3e-4);
  for (const char* name : {"laser_x_m", "laser_y_m"})
    EXPECT_NEAR(b["estimate"][name].get<double>(), 0.0, 3e-4) << name;
  EXPECT_NEAR(b["estimate"]["laser_theta_rad"].get<double>(), 0.0, 1e-3);
}

TEST(CliOdometryDrive, BeamsNeedTheLabelledScansBesideTheLandmarks) {
  TempDir dir;
  const auto r = runCli(inputs() + " --beams -o " + (dir / "out.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("scan_000000.pcd"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("labelled scan is missing"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.json"));
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
