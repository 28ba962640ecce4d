// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal diagnose` in static mode: a simulated room from one pose and the RPLIDAR recording.

#include <cmath>
#include <filesystem>
#include <functional>
#include <random>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/rng.hpp"
#include "diagnose_cli_util.hpp"
#include "io/model_io.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;
namespace fs = std::filesystem;

TEST(CliDiagnoseStatic, ARoomFromOnePoseIsDiagnosedInStaticModeAndTheEffectNamed) {
  TempDir dir;
  const fs::path scene = writeScene(dir.path(), "room", [](nlohmann::json& s) {
    s["landmarks"] = nlohmann::json::array();
    s["path"]["stops"] = 1;
    s["path"]["scans_per_stop"] = 120;
    s["sensor"]["effects"] = {{"incidence_noise_exponent", 1.0}};
    s["sensor"]["noise"]["sigma_e"] = 0.0015;
    s["walls"].push_back({{"x0_m", 1.0}, {"y0_m", 1.0}, {"x1_m", 2.5}, {"y1_m", 2.5}});
  });
  simulate(scene, dir / "room", 3);
  // The simulator kept the effect's key in the scene it simulated.
  EXPECT_EQ(json(dir / "room/truth.json")["scene"]["sensor"]["effects"]["incidence_noise_exponent"],
            1.0);
  const auto r = runCli("diagnose -q " + (dir / "room/scans").string() + " --out " +
                        (dir / "d").string() + " --replicas 9");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "incidence_noise\n");
  const auto j = json(dir / "d/diagnosis.json");
  EXPECT_EQ(j["mode"], "static");
  EXPECT_GE(j["baseline"]["walls"].size(), 4u);
  EXPECT_NEAR(
      j["extended_model"]["scene_keys"]["sensor.effects.incidence_noise_exponent"].get<double>(),
      1.0, 0.25);
  for (const auto& c : j["candidates"]) {
    if (c["effect"] == "heading_error") {
      EXPECT_TRUE(c["p_value"].is_null());
    }
  }
}

TEST(CliDiagnoseMeasured, RplidarRecordingIsAStaticRoom) {
  const fs::path bag = test::sharedData() / "rplidar_a2_room/rplidar_1.bag";
  if (!fs::exists(bag)) GTEST_SKIP() << "shared data absent: " << bag;
  TempDir dir;
  auto r = runCli("import -q --from rosbag1 " + bag.string() + " --out " + (dir / "seq").string() +
                  " --max-scans 300");
  if (r.exit_code != 0 && r.err.find("ROS") != std::string::npos)
    GTEST_SKIP() << "built without the ROS1 importer";
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runCli("diagnose -q " + (dir / "seq").string() + " --out " + (dir / "d").string() +
             " --replicas 5 --folds 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = json(dir / "d/diagnosis.json");
  EXPECT_EQ(j["mode"], "static");
  EXPECT_EQ(j["baseline"]["fitted"]["window_scans"], 0.0);  // it did not move
  EXPECT_GE(j["baseline"]["walls"].size(), 4u);
  // the bag's ranges are whole millimetres
  EXPECT_EQ(j["baseline"]["fitted"]["reading_grid_m"], 0.001);
  // What is established about this recording (docs/FINDINGS.md, on all 1319 scans): its noise has
  // heavy tails (a few readings up to 1.3 m off at depth discontinuities and dark furniture) and
  // grows with the incidence on the walls; the 1 mm grid is certain but far finer than the noise.
  // The named cause must be one of the two noise departures, and both must be significant.
  const std::string cause = j["primary_cause"];
  EXPECT_TRUE(cause == "heavy_tails" || cause == "incidence_noise") << cause;
  // The tails are explained by the beams' covariates, and the cause named is physical.
  ASSERT_TRUE(j["tails"].is_object());
  EXPECT_TRUE(j["tails"]["fitted"].get<bool>());
  EXPECT_NE(j["tails"]["cause"], "unknown");
  EXPECT_NE(cause, "heavy_tails");
  for (const auto& c : j["candidates"])
    if (c["effect"] == "heavy_tails" || c["effect"] == "incidence_noise") {
      EXPECT_TRUE(c["significant"].get<bool>()) << c["effect"];
    }
}

}  // namespace
}  // namespace lidarcal
