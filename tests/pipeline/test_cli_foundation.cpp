// SPDX-License-Identifier: BSD-3-Clause
// End-to-end checks of the `lidarcal` binary: simulate, info, determinism, bad input.

#include <cmath>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>

#include "io/scene_io.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;

std::string paperScene() { return (test::sourceDir() / "data/scenes/paper_field.json").string(); }

TEST(CliSimulate, WritesASequencePclCanOpenWithTheCommandedPoseAndTheTruth) {
  TempDir dir;
  const auto r =
      runCli("simulate --scene " + paperScene() + " --out " + (dir / "sim").string() + " --seed 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Truth truth = io::readTruth(dir / "sim/truth.json");
  ASSERT_EQ(truth.stops.size(), 10u);
  EXPECT_TRUE(std::filesystem::exists(dir / "sim/true_ranges.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "sim/scans/sequence.json"));
  for (std::size_t scan : {0u, 47u, 99u}) {
    const auto file = dir / ("sim/scans/scan_0000" + std::string(scan < 10 ? "0" : "") +
                             std::to_string(scan) + ".pcd");
    pcl::PointCloud<pcl::PointXYZ> cloud;
    ASSERT_EQ(pcl::io::loadPCDFile(file.string(), cloud), 0) << file;
    EXPECT_EQ(cloud.size(), 360u);
    const auto& stop = truth.stops[scan / 10];
    EXPECT_NEAR(cloud.sensor_origin_[0], stop.commanded.x_m, 1e-5);
    EXPECT_NEAR(cloud.sensor_origin_[1], stop.commanded.y_m, 1e-5);
    // The actual pose differs from the commanded one (sigma_s = 2 cm).
    EXPECT_GT(
        std::hypot(stop.actual.x_m - stop.commanded.x_m, stop.actual.y_m - stop.commanded.y_m),
        0.0);
  }
}

TEST(CliSimulate, SameSceneAndSeedGiveTheSameBytes) {
  TempDir dir;
  for (const char* name : {"a", "b"})
    ASSERT_EQ(runCli("simulate -q --scene " + paperScene() + " --out " + (dir / name).string() +
                     " --seed 7")
                  .exit_code,
              0);
  ASSERT_EQ(
      runCli("simulate -q --scene " + paperScene() + " --out " + (dir / "c").string() + " --seed 8")
          .exit_code,
      0);
  const auto a = test::snapshot(dir / "a"), b = test::snapshot(dir / "b"),
             c = test::snapshot(dir / "c");
  EXPECT_EQ(a.size(), 103u);  // 100 scans, sequence.json, truth.json, true_ranges.csv
  EXPECT_TRUE(a == b);
  EXPECT_NE(a.at("scans/scan_000000.pcd"), c.at("scans/scan_000000.pcd"));
}

TEST(CliSimulate, BundledExampleIsTheSimulationOfThePaperFieldWithSeed1) {
  // data/example is committed; regenerate it with
  //   lidarcal simulate --scene data/scenes/paper_field.json --out data/example --seed 1
  //   --overwrite
  TempDir dir;
  ASSERT_EQ(runCli("simulate -q --scene " + paperScene() + " --out " + (dir / "ex").string() +
                   " --seed 1")
                .exit_code,
            0);
  const auto fresh = test::snapshot(dir / "ex");
  const auto bundled = test::snapshot(test::sourceDir() / "data/example");
  EXPECT_EQ(bundled.size(), fresh.size());
  for (const auto& [name, bytes] : fresh) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(bundled.count(name));
    EXPECT_TRUE(bundled.at(name) == bytes);
  }
}

TEST(CliSimulate, UnreadableOrMalformedSceneIsReported) {
  TempDir dir;
  auto r = runCli("simulate --scene /nonexistent/scene.json --out " + (dir / "o").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/nonexistent/scene.json: file does not exist"), std::string::npos) << r.err;
  test::writeFile(dir / "s.json",
                  R"({"sensor": {"range_min_m": 0.2, "range_max_m": "far"}, "path": {}})");
  r = runCli("simulate --scene " + (dir / "s.json").string() + " --out " + (dir / "o").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("sensor.range_max_m: must be a number"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o"));  // no partial output
}

TEST(CliSimulate, RefusesToOverwriteAnExistingOutput) {
  TempDir dir;
  std::filesystem::create_directories(dir / "o");
  test::writeFile(dir / "o/keep.txt", "mine");
  const auto r = runCli("simulate --scene " + paperScene() + " --out " + (dir / "o").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--overwrite"), std::string::npos);
  EXPECT_EQ(test::readFile(dir / "o/keep.txt"), "mine");
}

class CliInfoBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(runCli("simulate -q --scene " + paperScene() + " --out " + (dir_ / "sim").string() +
                     " --stops 2 --scans-per-stop 2")
                  .exit_code,
              0);
    seq_ = dir_ / "sim/scans";
  }
  /// Runs `info` and checks the exit code, the message and that the input is unchanged.
  void expectError(const std::string& needle) {
    const auto before = test::snapshot(seq_);
    const auto r = runCli("info " + seq_.string());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    EXPECT_TRUE(before == test::snapshot(seq_));
  }
  TempDir dir_;
  std::filesystem::path seq_;
};

TEST_F(CliInfoBadInput, GoodSequenceIsSummarised) {
  const auto r = runCli("info " + seq_.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| scans | 4 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| stops | 2 "), std::string::npos) << r.out;
}

TEST_F(CliInfoBadInput, TruncatedPcd) {
  const auto file = seq_ / "scan_000001.pcd";
  const std::string bytes = test::readFile(file);
  test::writeFile(file, bytes.substr(0, bytes.size() - 100));
  expectError("scan_000001.pcd: DATA: file is truncated");
}

TEST_F(CliInfoBadInput, WrongFields) {
  const auto file = seq_ / "scan_000002.pcd";
  std::string bytes = test::readFile(file);
  bytes.replace(bytes.find("FIELDS x y z"), 12, "FIELDS a b c");
  test::writeFile(file, bytes);
  expectError("scan_000002.pcd: FIELDS: no 'x' field");
}

TEST_F(CliInfoBadInput, MissingViewpoint) {
  const auto file = seq_ / "scan_000000.pcd";
  std::string bytes = test::readFile(file);
  const auto at = bytes.find("VIEWPOINT");
  bytes.erase(at, bytes.find('\n', at) - at + 1);
  test::writeFile(file, bytes);
  expectError("scan_000000.pcd: VIEWPOINT: missing");
}

TEST_F(CliInfoBadInput, EmptyDirectory) {
  for (const auto& e : std::filesystem::directory_iterator(seq_)) std::filesystem::remove(e.path());
  expectError("holds no .pcd file");
}

TEST(CliGeneral, HelpAndUnknownCommand) {
  EXPECT_EQ(runCli("--help").exit_code, 0);
  EXPECT_EQ(runCli("simulate --help").exit_code, 0);
  const auto r = runCli("frobnicate");
  EXPECT_NE(r.exit_code, 0);
}

}  // namespace
}  // namespace lidarcal
