// SPDX-License-Identifier: BSD-3-Clause
// Inputs that are not errors, documented in docs/ERRORS.md beside the bad-input catalogue: scans
// whose beam count varies, landmarks all on one side of the path.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bad_input_builders.hpp"
#include "bad_input_util.hpp"
#include "io/import_test_util.hpp"

namespace lidarcal {
namespace {

using namespace test;

TEST(BadInputWarnings,
     ScansWithDifferentBeamCountsCalibrateWithAWarningAndAModelWithoutABeamCount) {
  TempDir dir;
  const fs::path in = dir / "in";
  // The paper's field seen by a sensor whose beam count varies (YDLIDAR X4 does): odd stops
  // with 360 beams, even stops with 359, and no `beams` in sequence.json.
  const std::string paper = readFile(scenePath("paper_field.json"));
  fs::create_directories(in / "scans");
  writeFile(dir / "a.json", replaceAll(paper, "\"scans_per_stop\": 10", "\"scans_per_stop\": 2"));
  writeFile(dir / "b.json",
            replaceAll(replaceAll(paper, "\"scans_per_stop\": 10", "\"scans_per_stop\": 2"),
                       "\"angle_increment_deg\": 1.0", "\"angle_increment_deg\": 1.0027855"));
  writeFile(dir / "b.json",
            replaceAll(readFile(dir / "b.json"), "\"beams\": 360", "\"beams\": 359"));
  for (const char* s : {"a", "b"})
    ASSERT_EQ(runCli("simulate -q --scene " + (dir / (std::string(s) + ".json")).string() +
                     " --out " + (dir / s).string() + " --seed 5")
                  .exit_code,
              0);
  for (int i = 0; i < 20; ++i) {
    const std::string name =
        "scan_0000" + std::string(i < 10 ? "0" : "") + std::to_string(i) + ".pcd";
    fs::copy_file(dir / ((i / 2) % 2 ? "b" : "a") / "scans" / name, in / "scans" / name);
  }
  auto meta = nlohmann::json::parse(readFile(dir / "a/scans/sequence.json"));
  meta.erase("beams");
  writeFile(in / "scans/sequence.json", meta.dump());
  const auto before = snapshot(in);
  const auto r =
      runCli("calibrate -q " + (in / "scans").string() + " --out " + (dir / "m.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("varies from 359 to 360"), std::string::npos) << r.err;
  EXPECT_TRUE(snapshot(in) == before);
  const auto model = nlohmann::json::parse(readFile(dir / "m.json"));
  EXPECT_TRUE(model["sensor"]["beams"].is_null());
  // The bias is still found: the simulated one is f(3) = 3.24 m.
  const auto& a = model["bias"]["alpha"];
  double f3 = 0.0;
  for (std::size_t i = a.size(); i-- > 0;) f3 = f3 * 3.0 + a[i].get<double>();
  EXPECT_NEAR(f3, 0.0525 + 0.8838 * 3 + 0.0584 * 9, 0.03);
  // And the model corrects every scan of that sequence.
  const auto c = runCli("correct -q " + (in / "scans").string() + " --model " +
                        (dir / "m.json").string() + " --out " + (dir / "c").string());
  EXPECT_EQ(c.exit_code, 0) << c.err;
  EXPECT_NE(c.err.find("warning: "), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("varies from 359 to 360"), std::string::npos) << c.err;
  // A model of one beam count refuses the scans with the other, naming the first.
  auto fixed = nlohmann::json::parse(readFile(dir / "m.json"));
  fixed["sensor"]["beams"] = 360;
  writeFile(dir / "m360.json", fixed.dump());
  const auto f = runCli("correct " + (in / "scans").string() + " --model " +
                        (dir / "m360.json").string() + " --out " + (dir / "c360").string());
  EXPECT_EQ(f.exit_code, 2);
  EXPECT_NE(f.err.find("scan_000002.pcd: POINTS: has 359 beams"), std::string::npos) << f.err;
  EXPECT_FALSE(fs::exists(dir / "c360"));
  EXPECT_TRUE(snapshot(in) == before);
}

TEST(BadInputGeometry, LandmarksAllOnOneSideOfThePathStillCalibrate) {
  // Alhashimi et al. 2021 places poles on both sides of the path; on one side only, the bearing
  // lines from the stops still cross at a wide angle, so this is not degenerate: the bias is
  // recovered.
  TempDir dir;
  const Ws w{dir / "in", dir / "out", fixtures()};
  ASSERT_NO_FATAL_FAILURE(simulated(scene(
      R"({"x_m": 1.5, "y_m": 0.75, "radius_m": 0.12}, {"x_m": 0.3, "y_m": 2.2, "radius_m": 0.12},
      {"x_m": 2.4, "y_m": 3.4, "radius_m": 0.12}, {"x_m": 3.6, "y_m": 1.4, "radius_m": 0.12}, {"x_m": 1.2, "y_m": 3.9, "radius_m": 0.12})",
      path(10, 3)))(w));
  const auto r = runCli("calibrate -q " + (w.in / "sim/scans").string() + " --out " +
                        (dir / "m.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto a = nlohmann::json::parse(readFile(dir / "m.json"))["bias"]["alpha"];
  for (double d : {1.0, 2.0, 3.0}) {
    double f = 0.0;
    for (std::size_t i = a.size(); i-- > 0;) f = f * d + a[i].get<double>();
    EXPECT_NEAR(f, 0.0525 + 0.8838 * d + 0.0584 * d * d, 0.03) << "d = " << d;
  }
}

}  // namespace
}  // namespace lidarcal
