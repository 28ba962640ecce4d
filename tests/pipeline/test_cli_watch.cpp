// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal watch` end to end: a simulated drive replayed against a model calibrated on another
// drive of the same scene, clean and with a change injected; what it refuses and when it can
// test nothing.
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;
namespace fs = std::filesystem;

nlohmann::json readJson(const fs::path& p) { return nlohmann::json::parse(test::readFile(p)); }

/// A drive of `scans` scans of data/scenes/driving_large_poles.json, simulated with `seed`.
fs::path drive(const fs::path& dir, const std::string& name, int scans, int seed) {
  nlohmann::json s = readJson(test::sourceDir() / "data" / "scenes" / "driving_large_poles.json");
  s["path"]["scans"] = scans;
  test::writeFile(dir / (name + ".json"), s.dump(1));
  const auto r = runCli("simulate -q --scene " + (dir / (name + ".json")).string() + " -o " +
                        (dir / name).string() + " --seed " + std::to_string(seed));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return dir / name / "scans";
}

/// The drives every test watches: one to calibrate on (900 scans, model.json) and one to watch
/// (1200 scans); `complete` is written last.
void makeDrives(const fs::path& dir) {
  const fs::path cal = drive(dir, "calibration", 900, 7);
  const auto r = runCli("calibrate -q " + cal.string() + " -o " + (dir / "model.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  drive(dir, "watched", 1200, 8);
  test::writeFile(dir / "complete", "");
}

/// The directory a ctest run shares among this suite's processes (tests/CMakeLists.txt: the
/// fixture test below makes the drives there once), when it is set.
const char* sharedDrives() { return std::getenv("LIDARCAL_TEST_FIXTURE_DIR"); }

TEST(CliWatchFixture, MakesTheDrivesOnce) {
  if (!sharedDrives())
    GTEST_SKIP() << "LIDARCAL_TEST_FIXTURE_DIR is not set: each suite makes its own";
  const fs::path dir = sharedDrives();
  fs::remove_all(dir);
  fs::create_directories(dir);
  makeDrives(dir);
}

class CliWatch : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (sharedDrives() && fs::exists(fs::path(sharedDrives()) / "complete")) {
      base_ = sharedDrives();
      return;
    }
    own_ = new TempDir;
    base_ = own_->path();
    makeDrives(base_);
  }
  static void TearDownTestSuite() { delete own_; }
  static fs::path model() { return base_ / "model.json"; }
  static fs::path watched() { return base_ / "watched" / "scans"; }
  static TempDir* own_;
  static fs::path base_;
};
TempDir* CliWatch::own_ = nullptr;
fs::path CliWatch::base_;

TEST_F(CliWatch, AnInjectedOffsetIsAnAlarmAfterItsScanAndTheCleanPartIsNot) {
  TempDir out;
  const auto before = test::snapshot(watched());
  const auto r = runCli("watch -q " + watched().string() + " --model " + model().string() +
                        " --inject 20@800 -o " + (out / "w").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;  // an alarm is a result, not an error
  EXPECT_NE(r.out.find("alarm at scan"), std::string::npos) << r.out;
  const auto t = readJson(out / "w" / "timeline.json");
  EXPECT_EQ(t["format"], "lidarcal-watch/1");
  EXPECT_EQ(t["injected"]["from_scan"], 800);
  std::size_t early = 0, late = 0, tests = 0;
  for (const auto& c : t["checks"]) {
    if (!c.contains("alarm")) continue;
    ++tests;
    (c["decided_at_scan"].get<std::size_t>() < 800 ? early : late) += c["alarm"].get<bool>();
  }
  EXPECT_GE(tests, 5u);
  EXPECT_EQ(early, 0u);
  EXPECT_GE(late, 1u);
  EXPECT_EQ(t["summary"]["level"], "ERROR");
  EXPECT_TRUE(fs::exists(out / "w" / "timeline.png") || r.err.find("no plot") != std::string::npos);
  test::expectSameFiles(before, test::snapshot(watched()));  // the input untouched
}

TEST_F(CliWatch, LearnModeSwitchesAfterTheChangeAndWritesTheNewModel) {
  TempDir out;
  const auto r = runCli("watch -q " + watched().string() + " --model " + model().string() +
                        " --mode learn --inject 25@700 -o " + (out / "w").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto t = readJson(out / "w" / "timeline.json");
  ASSERT_GE(t["summary"]["switches"].get<int>(), 1) << t["summary"].dump();
  std::string file;
  for (const auto& f : t["refits"])
    if (f["switched"].get<bool>() && file.empty()) {
      file = f["model_file"];
      EXPECT_GE(f["first_scan"].get<std::size_t>() + 100, 700u);
    }
  ASSERT_FALSE(file.empty());
  EXPECT_NE(r.out.find("(timeline.json, models/"), std::string::npos) << r.out;
  // The model learnt reads 25 mm longer than the one given where both were fitted.
  const auto learnt = readJson(out / "w" / file);
  const auto given = readJson(model());
  auto bias = [](const nlohmann::json& m, double d) {
    double f = 0.0, p = 1.0;
    for (double a : m["bias"]["alpha"]) f += a * p, p *= d;
    return f;
  };
  for (double d : {1.5, 2.5}) EXPECT_NEAR(bias(learnt, d) - bias(given, d), 0.025, 0.006) << d;
}

TEST_F(CliWatch, RefusesWhatItCannotUse) {
  TempDir out;
  auto r = runCli("watch -q " + watched().string() + " -o " + (out / "a").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--model"), std::string::npos) << r.err;
  r = runCli("watch -q " + watched().string() + " --model " + model().string() +
             " --inject x@5 -o " + (out / "b").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--inject"), std::string::npos) << r.err;
  r = runCli("watch -q " + watched().string() + " --model " + model().string() +
             " --check-bias-replicas 101 -o " + (out / "r").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--check-bias-replicas"), std::string::npos) << r.err;
  auto m = readJson(model());
  m.erase("alpha_covariance");
  test::writeFile(out / "nocov.json", m.dump());
  r = runCli("watch -q " + watched().string() + " --model " + (out / "nocov.json").string() +
             " -o " + (out / "c").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("alpha_covariance"), std::string::npos) << r.err;
}

TEST_F(CliWatch, ARobotStandingStillCanTestNothingAndSaysWhatToRecord) {
  TempDir out;
  // The bundled example stops 10 times with 10 scans each: too little travel for one test.
  const auto r = runCli("watch " + (test::sourceDir() / "data/example/scans").string() +
                        " --model " + model().string() + " -o " + (out / "w").string());
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("record a longer drive"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(out / "w" / "timeline.json"));
  // Without a test there is no point to draw: no plot, said plainly, and no gnuplot failure.
  EXPECT_NE(r.err.find("no plot (no test was made"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("gnuplot failed"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "w" / "timeline.png"));
  EXPECT_NE(r.out.find("(timeline.json)"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace lidarcal
