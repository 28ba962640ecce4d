// SPDX-License-Identifier: BSD-3-Clause
// Wall-to-wall spans in REF.json end to end: `calibrate --reference` on a simulated room from one
// stop (the room's true dimensions play the laser meter), the report it writes, `evaluate` of the
// spans on the corrected scans, every way a span can be wrong named by its REF.json field, and
// the RPLIDAR A2 room of ../shared/data with its laser-meter spans.

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;
namespace fs = std::filesystem;

nlohmann::json json(const fs::path& p) { return nlohmann::json::parse(test::readFile(p)); }

/// A room 6 m x 4.5 m (x from -2.5 to 3.5, y from -2 to 2.5) with a cabinet 0.4 m deep against
/// the wall x = 3.5 for y < 0, one stop at the origin turned 20 degrees; the sensor reads
/// f(d) = 0.03 + d. `open_side`: without the wall x = -2.5 (nothing there within the sensor's
/// range). Normal directions in the sensor frame: x = 3.5 and the cabinet -20 deg, x = -2.5
/// 160 deg, y = -2 -110 deg, y = 2.5 70 deg.
std::string roomScene(bool open_side = false) {
  nlohmann::json walls = nlohmann::json::array();
  for (const auto& w : std::vector<std::array<double, 4>>{{-2.5, -2.0, 3.5, -2.0},
                                                          {3.5, -2.0, 3.5, 2.5},
                                                          {3.5, 2.5, -2.5, 2.5},
                                                          {3.1, -2.0, 3.1, 0.0},
                                                          {3.1, 0.0, 3.5, 0.0}})
    walls.push_back({{"x0_m", w[0]}, {"y0_m", w[1]}, {"x1_m", w[2]}, {"y1_m", w[3]}});
  if (!open_side) walls.push_back({{"x0_m", -2.5}, {"y0_m", 2.5}, {"x1_m", -2.5}, {"y1_m", -2.0}});
  return nlohmann::json{{"sensor",
                         {{"beams", 360},
                          {"range_min_m", 0.15},
                          {"range_max_m", 8.0},
                          {"bias_alpha", {0.03, 1.0}},
                          {"noise", {{"kind", "squared"}, {"sigma_e", 0.001}}}}},
                        {"path",
                         {{"start", {{"x_m", 0.0}, {"y_m", 0.0}, {"yaw_deg", 20.0}}},
                          {"stops", 1},
                          {"scans_per_stop", 10}}},
                        {"walls", walls}}
      .dump();
}

void simulateRoom(const TempDir& dir, bool open_side = false) {
  test::writeFile(dir / "scene.json", roomScene(open_side));
  const auto r = runCli("simulate -q --scene " + (dir / "scene.json").string() + " --out " +
                        (dir / "room").string() + " --seed 5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

/// REF.json with the room's three spans (or `spans` as given).
std::string reference(
    const std::string& spans =
        R"([{"stop": 0, "bearing_a_deg": -20, "bearing_b_deg": 160, "distance_m": 6.0},
    {"stop": 0, "bearing_a_deg": -20, "bearing_b_deg": 160, "distance_m": 5.6},
    {"stop": 0, "bearing_a_deg": -110, "bearing_b_deg": 70, "distance_m": 4.5}])") {
  return R"({"format": "lidarcal-reference/1", "spans": )" + spans + "}";
}

TEST(CliSpans, ARoomFromOneStopCalibratesFromItsSpansAndWritesTheReport) {
  TempDir dir;
  simulateRoom(dir);
  test::writeFile(dir / "ref.json", reference());
  const std::string seq = (dir / "room/scans").string();
  const auto cal =
      runCli("calibrate -q " + seq + " --reference " + (dir / "ref.json").string() + " --out " +
             (dir / "model.json").string() + " --report " + (dir / "report").string());
  ASSERT_EQ(cal.exit_code, 0) << cal.err;
  EXPECT_NE(cal.out.find("| spans[2] | 0 |"), std::string::npos) << "the spans on stdout:\n"
                                                                 << cal.out;
  EXPECT_NE(cal.out.find("left out"), std::string::npos) << cal.out;
  const auto m = json(dir / "model.json");
  EXPECT_EQ(m["method"], "reference");
  // The truth: f(3) - 3 = 30 mm, within 3 standard errors of what the fit says.
  const std::vector<double> alpha = m["bias"]["alpha"];
  const std::vector<double> cov = m["alpha_covariance"];
  const std::size_t n = alpha.size();
  double f3 = 0.0, var = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    f3 += alpha[i] * std::pow(3.0, double(i));
    for (std::size_t j = 0; j < n; ++j)
      var += std::pow(3.0, double(i)) * cov[i * n + j] * std::pow(3.0, double(j));
  }
  EXPECT_GT(var, 0.0);
  EXPECT_LT(std::abs(f3 - 3.03), 3.0 * std::sqrt(var)) << f3 << " +- " << std::sqrt(var);
  // The report: written, about the readings the spans place (no landmarks), with its data.
  ASSERT_TRUE(fs::exists(dir / "report/report.md"));
  const std::string report = test::readFile(dir / "report/report.md");
  EXPECT_NE(report.find("of known true distance"), std::string::npos) << report;
  EXPECT_NE(report.find("**reference**"), std::string::npos) << report;
  EXPECT_TRUE(fs::file_size(dir / "report/distance.dat") > 0);

  // Measured on the corrected scans, the spans come out right.
  const auto ev =
      runCli("evaluate -q " + seq + " --reference " + (dir / "ref.json").string() + " --model " +
             (dir / "model.json").string() + " --out " + (dir / "eval.json").string());
  ASSERT_EQ(ev.exit_code, 0) << ev.err;
  const auto e = json(dir / "eval.json");
  const double raw = e["raw"]["spans"]["rms_error_m"],
               corrected = e["corrected"]["spans"]["rms_error_m"];
  EXPECT_NEAR(raw, 0.06, 0.01);  // two readings 3 cm long in every span
  EXPECT_LT(corrected, 0.01);
}

TEST(CliSpans, EveryWayASpanCanBeWrongIsNamedByItsField) {
  TempDir dir;
  simulateRoom(dir);
  const std::string seq = (dir / "room/scans").string();
  struct Case {
    std::string spans;
    int exit_code;
    std::vector<std::string> names;
  };
  const std::vector<Case> cases = {
      // No wall where bearing_b_deg points: exit 3 with the walls the stop shows.
      {R"([{"stop": 0, "bearing_a_deg": -20, "bearing_b_deg": 115, "distance_m": 6.0}])",
       3,
       {"spans[0].bearing_b_deg", "no wall within 20 deg of 115 deg", "160 deg at"}},
      // Both bearings on one wall: a span's walls face each other across the sensor (exit 2).
      {R"([{"stop": 0, "bearing_a_deg": -20, "bearing_b_deg": -10, "distance_m": 6.0}])",
       2,
       {"spans[0].bearing_b_deg", "opposite sides"}},
      // No pair of walls there comes near distance_m.
      {R"([{"stop": 0, "bearing_a_deg": -20, "bearing_b_deg": 160, "distance_m": 9.0}])",
       3,
       {"spans[0].distance_m"}},
      // Walls 90 degrees apart are not parallel.
      {R"([{"stop": 0, "bearing_a_deg": -20, "bearing_b_deg": 70, "distance_m": 4.5}])",
       3,
       {"spans[0].bearing_b_deg", "not parallel"}},
      {R"([{"stop": 0, "bearing_a_deg": -20, "bearing_b_deg": 160, "distance": 6.0}])",
       2,
       {"spans[0].distance"}},
      {R"([{"stop": 1, "bearing_a_deg": -20, "bearing_b_deg": 160, "distance_m": 6.0}])",
       2,
       {"spans[0].stop"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.spans);
    test::writeFile(dir / "ref.json", reference(c.spans));
    const auto r = runCli("calibrate -q " + seq + " --reference " + (dir / "ref.json").string() +
                          " --out " + (dir / "m.json").string());
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    for (const auto& name : c.names)
      EXPECT_NE(r.err.find(name), std::string::npos) << name << " in\n" << r.err;
    EXPECT_NE(r.err.find("ref.json"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "m.json"));
  }
  // The self-calibration takes no spans.
  test::writeFile(dir / "ref.json", reference());
  const auto combined =
      runCli("calibrate -q " + seq + " --reference " + (dir / "ref.json").string() +
             " --reference-fit combined --out " + (dir / "m.json").string());
  EXPECT_EQ(combined.exit_code, 2) << combined.err;
  EXPECT_NE(combined.err.find("spans"), std::string::npos) << combined.err;
}

// A room open on one side: the span's second wall is not there.
TEST(CliSpans, ASpanToAWallTheStopDoesNotSeeIsRefusedNamingIt) {
  TempDir dir;
  simulateRoom(dir, true);
  test::writeFile(
      dir / "ref.json",
      reference(R"([{"stop": 0, "bearing_a_deg": -20, "bearing_b_deg": 160, "distance_m": 6.0}])"));
  const auto r = runCli("calibrate -q " + (dir / "room/scans").string() + " --reference " +
                        (dir / "ref.json").string() + " --out " + (dir / "m.json").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("spans[0].bearing_b_deg: no wall within 20 deg of 160 deg"),
            std::string::npos)
      << r.err;
}

// ---- The RPLIDAR A2 in an office room, one static pose (../shared/data/rplidar_a2_room). The
// spans are the laser-meter distances of distance_comparison.md (lines 1-3 wall to wall, 4-5
// wall to cabinet, 6 sideboard to wall across the room); the directions of the walls' normals
// in the sensor frame are those the refusal of `run` lists for this recording. ----

const std::string kRplidarSpans = R"([
  {"stop": 0, "bearing_a_deg": -50, "bearing_b_deg": 130, "distance_m": 6.155},
  {"stop": 0, "bearing_a_deg": -50, "bearing_b_deg": 130, "distance_m": 6.150},
  {"stop": 0, "bearing_a_deg": -50, "bearing_b_deg": 130, "distance_m": 6.147},
  {"stop": 0, "bearing_a_deg": -50, "bearing_b_deg": 130, "distance_m": 5.709},
  {"stop": 0, "bearing_a_deg": -50, "bearing_b_deg": 130, "distance_m": 5.709},
  {"stop": 0, "bearing_a_deg": -140, "bearing_b_deg": 40, "distance_m": 4.777}])";

TEST(CliSpansRplidar, TheRoomCalibratesFromItsLaserMeterSpans) {
  const fs::path bag = test::sharedData() / "rplidar_a2_room/rplidar_1.bag";
  if (!fs::exists(bag)) GTEST_SKIP() << bag << " is absent";
  TempDir dir;
  const auto imp =
      runCli("import -q --from rosbag1 " + bag.string() + " --out " + (dir / "room").string());
  if (imp.exit_code == 2 && imp.err.find("ROS1") != std::string::npos)
    GTEST_SKIP() << "no ROS1 reader in this build";
  ASSERT_EQ(imp.exit_code, 0) << imp.err;
  const std::string seq = (dir / "room").string();
  // One pose: the self-calibration refuses, naming what this recording can do instead.
  const auto run = runCli("run -q " + seq + " --out " + (dir / "run").string());
  EXPECT_EQ(run.exit_code, 3) << run.err;
  for (const char* way :
       {"--reference REF.json", "wall-to-wall spans", "lidarcal diagnose", "deg at"})
    EXPECT_NE(run.err.find(way), std::string::npos) << way << " in\n" << run.err;

  test::writeFile(dir / "ref.json", reference(kRplidarSpans));
  const auto cal = runCli("calibrate -q " + seq + " --reference " + (dir / "ref.json").string() +
                          " --out " + (dir / "model.json").string());
  ASSERT_EQ(cal.exit_code, 0) << cal.err;
  const auto m = json(dir / "model.json");
  const double a0 = m["bias"]["alpha"][0], se0 = m["bias"]["standard_error"][0];
  // The authors found the lidar's wall-to-wall distances 3-6 cm too long: a positive offset.
  EXPECT_GT(a0, 2.0 * se0) << a0 << " +- " << se0;
  EXPECT_LT(a0, 0.05);
  const auto ev =
      runCli("evaluate -q " + seq + " --reference " + (dir / "ref.json").string() + " --model " +
             (dir / "model.json").string() + " --out " + (dir / "eval.json").string());
  ASSERT_EQ(ev.exit_code, 0) << ev.err;
  const auto e = json(dir / "eval.json");
  for (const auto& entry : e["raw"]["spans"]["entries"]) {
    ASSERT_EQ(entry["status"], "ok") << entry.dump();
    EXPECT_GT(entry["error_m"].get<double>(), 0.0) << entry.dump();
  }
  EXPECT_LT(e["corrected"]["spans"]["rms_error_m"].get<double>(),
            0.5 * e["raw"]["spans"]["rms_error_m"].get<double>());
}

}  // namespace
}  // namespace lidarcal
