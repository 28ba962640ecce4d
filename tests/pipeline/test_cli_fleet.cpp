// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal fleet` end to end on a simulated fleet: 21 sensors, each simulated and calibrated
// twice (`lidarcal simulate`, `lidarcal calibrate`) with the paper field's bias; the second time
// one sensor's offset alpha_0 is 2 cm larger. The report flags exactly that sensor (moved since
// its previous calibration, and apart from the fleet), its rows agree with the models it read,
// and bad manifests are refused naming the file, line and field.

#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "calibration/fleet.hpp"
#include "io/model_io.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;
namespace fs = std::filesystem;

constexpr int kSensors = 21;
constexpr int kMoved = 7;

std::string sensorName(int i) {
  return std::string("robot") + (i < 10 ? "0" : "") + std::to_string(i);
}

/// Simulates and calibrates every sensor in both weeks under `dir`; returns the manifest's path.
/// Seeds: 100 + sensor in the first week, 200 + sensor in the second.
fs::path calibrateFleet(const TempDir& dir) {
  const nlohmann::json base =
      nlohmann::json::parse(test::readFile(test::sourceDir() / "data/scenes/paper_field.json"));
  std::string manifest = "sensor,date,model\n";
  for (int week = 1; week <= 2; ++week)
    for (int i = 0; i < kSensors; ++i) {
      nlohmann::json scene = base;
      scene["sensor"]["name"] = sensorName(i);
      scene["path"]["scans_per_stop"] = 3;  // small recordings: the test stays fast
      if (week == 2 && i == kMoved)
        scene["sensor"]["bias_alpha"][0] = scene["sensor"]["bias_alpha"][0].get<double>() + 0.02;
      const std::string tag = sensorName(i) + "_" + std::to_string(week);
      test::writeFile(dir / (tag + ".json"), scene.dump());
      const auto sim = runCli("-q simulate --scene " + (dir / (tag + ".json")).string() + " -o " +
                              (dir / tag).string() + " --seed " + std::to_string(100 * week + i));
      EXPECT_EQ(sim.exit_code, 0) << sim.err;
      const auto cal = runCli("-q calibrate " + (dir / tag / "scans").string() + " -o " +
                              (dir / (tag + "_model.json")).string());
      EXPECT_EQ(cal.exit_code, 0) << cal.err;
      manifest +=
          sensorName(i) + (week == 1 ? ",2024-05-06," : ",2024-05-13,") + tag + "_model.json\n";
    }
  test::writeFile(dir / "fleet.csv", manifest);
  return dir / "fleet.csv";
}

TEST(FleetCli, FlagsTheOneSensorWhoseOffsetMovedByTwoCentimetres) {
  TempDir dir;
  const fs::path manifest = calibrateFleet(dir);
  const auto r =
      runCli("fleet --manifest " + manifest.string() + " -o " + (dir / "report").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("robot07 (2024-05-13): bias moved since its previous calibration"),
            std::string::npos)
      << r.out;
  const nlohmann::json report =
      nlohmann::json::parse(test::readFile(dir / "report" / "fleet.json"));
  EXPECT_EQ(report["flagged"], nlohmann::json::array({"robot07"}));
  ASSERT_EQ(report["sensors"].size(), static_cast<std::size_t>(kSensors));
  const std::vector<double> distances =
      report["settings"]["distances_m"].get<std::vector<double>>();
  for (int i = 0; i < kSensors; ++i) {
    SCOPED_TRACE(sensorName(i));
    const nlohmann::json& row = report["sensors"][static_cast<std::size_t>(i)];
    EXPECT_EQ(row["sensor"], sensorName(i));
    EXPECT_EQ(row["date"], "2024-05-13");
    EXPECT_EQ(row["flags"].size(), i == kMoved ? 2u : 0u);
    EXPECT_TRUE(row["moved"]["tested"].get<bool>());
    EXPECT_TRUE(row["outlier"]["tested"].get<bool>());
    // The row is the second week's model, read back: bias and standard error at every distance.
    const auto model = io::readModel(dir / (sensorName(i) + "_2_model.json"));
    const auto expected = calibration::biasAt(model, distances);
    for (std::size_t j = 0; j < distances.size(); ++j) {
      EXPECT_DOUBLE_EQ(row["bias"][j]["bias_m"].get<double>(), expected[j].bias_m);
      EXPECT_DOUBLE_EQ(row["bias"][j]["se_m"].get<double>(), expected[j].se_m);
    }
  }
  const std::string md = test::readFile(dir / "report" / "fleet.md");
  EXPECT_NE(md.find("flagged: **1**: robot07."), std::string::npos);
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_TRUE(fs::exists(dir / "report" / "fleet_bias.svg"));
  }

  // The second week's models alone (no history): only the fleet comparison, the same sensor.
  std::string models;
  for (int i = 0; i < kSensors; ++i)
    models += " " + (dir / (sensorName(i) + "_2_model.json")).string();
  ASSERT_EQ(runCli("fleet" + models + " -o " + (dir / "snapshot").string()).exit_code, 0);
  const nlohmann::json snapshot =
      nlohmann::json::parse(test::readFile(dir / "snapshot" / "fleet.json"));
  EXPECT_EQ(snapshot["flagged"], nlohmann::json::array({"robot07"}));
  EXPECT_EQ(snapshot["sensors"][kMoved]["flags"], nlohmann::json::array({"outlier"}));
}

TEST(FleetCli, BadInputsAreRefusedNamingFileLineAndField) {
  TempDir dir;
  const std::string example = (test::sourceDir() / "data/example/scans").string();
  ASSERT_EQ(runCli("-q calibrate " + example + " -o " + (dir / "m.json").string()).exit_code, 0);
  auto refused = [&](const std::string& csv, const std::vector<std::string>& words) {
    test::writeFile(dir / "bad.csv", csv);
    const auto r =
        runCli("fleet --manifest " + (dir / "bad.csv").string() + " -o " + (dir / "out").string());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    for (const auto& w : words)
      EXPECT_NE(r.err.find(w), std::string::npos) << "missing '" << w << "' in: " << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
  };
  refused("sensor,model\n", {"bad.csv", "line 1", "sensor,date,model"});
  refused("sensor,date,model\na,last week,m.json\n", {"bad.csv", "line 2", "date", "ISO 8601"});
  refused("sensor,date,model\na,2024-01-01,m.json\na,2024-01-01,m.json\n",
          {"m.json", "date", "two calibrations dated 2024-01-01"});
  refused("sensor,date,model\na,2024-01-01,missing.json\n", {"missing.json"});
  // A model without a sensor name cannot be told apart from the others without a manifest.
  nlohmann::json unnamed = nlohmann::json::parse(test::readFile(dir / "m.json"));
  unnamed["sensor"]["name"] = "";
  test::writeFile(dir / "unnamed.json", unnamed.dump());
  const auto r =
      runCli("fleet " + (dir / "unnamed.json").string() + " -o " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unnamed.json: sensor.name"), std::string::npos) << r.err;
  const auto none = runCli("fleet -o " + (dir / "out").string());
  EXPECT_EQ(none.exit_code, 2);
  const auto distances = runCli("fleet " + (dir / "m.json").string() + " --distances 2,1 -o " +
                                (dir / "out").string());
  EXPECT_EQ(distances.exit_code, 2);
  EXPECT_NE(distances.err.find("increasing"), std::string::npos) << distances.err;
}

}  // namespace
}  // namespace lidarcal
