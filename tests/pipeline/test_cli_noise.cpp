// SPDX-License-Identifier: BSD-3-Clause
// End-to-end: simulate an observation scene, estimate its noise with both methods, convert
// detection output; errors and determinism.

#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "io/noise_json.hpp"
#include "io/observations_csv.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;

// A small two-sensor scene with known noise (experiment 2's sensors, some process noise).
const char* kScene = R"({"kind": "observations", "name": "cli test",
  "sensors": [{"range_var_m2": 0.3, "bearing_var_rad2": 0.4, "range_mean_m": 0.2},
              {"range_var_m2": 0.5, "bearing_var_rad2": 0.6}],
  "process_noise": {"dx_m2": 0.004, "dy_m2": 0.004, "dtheta_rad2": 0.0005},
  "landmarks": [{"x_m": -3, "y_m": -2}, {"x_m": 4, "y_m": -3}, {"x_m": 9, "y_m": 1}, {"x_m": 7, "y_m": 9},
                {"x_m": 1, "y_m": 9}, {"x_m": -3, "y_m": 5}, {"x_m": 3, "y_m": 3}, {"x_m": 10, "y_m": 6}],
  "trajectory": {"motions": [{"dx_m": 1, "count": 5}, {"dx_m": 1, "dtheta_deg": 90}], "repeat": 24}})";

nlohmann::json readJson(const std::filesystem::path& p) {
  return nlohmann::json::parse(test::readFile(p));
}

TEST(CliNoise, SimulateWritesObservationsOdometryAndTruthDeterministically) {
  TempDir dir;
  test::writeFile(dir / "scene.json", kScene);
  for (const char* name : {"a", "b"})
    ASSERT_EQ(runCli("simulate -q --scene " + (dir / "scene.json").string() + " --out " +
                     (dir / name).string() + " --seed 3")
                  .exit_code,
              0);
  const auto a = test::snapshot(dir / "a"), b = test::snapshot(dir / "b");
  EXPECT_EQ(a.size(), 3u);
  EXPECT_TRUE(a == b);
  EXPECT_EQ(io::readOdometry(dir / "a/odometry.csv").size(), 1u + 24u * 6u);
  EXPECT_EQ(io::readObservations(dir / "a/observations.csv").size(), (1u + 24u * 6u) * 2u * 8u);
  const io::NoiseTruth truth = io::readNoiseTruth(dir / "a/noise_truth.json");
  EXPECT_EQ(truth.poses.size(), 1u + 24u * 6u);
  EXPECT_DOUBLE_EQ(io::readNoiseSetting(dir / "a/noise_truth.json").sensors[0].range_mean_m, 0.2);
}

TEST(CliNoise, MlRecoversTheNoiseAndWritesTheResultAndPlots) {
  TempDir dir;
  test::writeFile(dir / "scene.json", kScene);
  ASSERT_EQ(runCli("simulate -q --scene " + (dir / "scene.json").string() + " --out " +
                   (dir / "sim").string() + " --seed 5")
                .exit_code,
            0);
  const auto r =
      runCli("noise-consistency -q --observations " + (dir / "sim/observations.csv").string() +
             " --odometry " + (dir / "sim/odometry.csv").string() + " --method ml --out " +
             (dir / "ml.json").string() + " --plot " + (dir / "plots").string() + " --truth " +
             (dir / "sim/noise_truth.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = readJson(dir / "ml.json");
  EXPECT_EQ(j["method"], "ml");
  EXPECT_EQ(j["status"], "ok");
  const double truth_var[2][2] = {{0.3, 0.4}, {0.5, 0.6}};
  for (int s = 0; s < 2; ++s) {
    const auto& e = j["sensors"][s];
    EXPECT_NEAR(e["range_var_m2"].get<double>(), truth_var[s][0],
                4 * e["range_var_se_m2"].get<double>());
    EXPECT_NEAR(e["bearing_var_rad2"].get<double>(), truth_var[s][1],
                4 * e["bearing_var_se_rad2"].get<double>());
  }
  EXPECT_NEAR(j["sensors"][0]["range_mean_m"].get<double>(), 0.2,
              4 * j["sensors"][0]["range_mean_se_m"].get<double>());
  for (const char* key : {"process_var", "objective_trace", "evaluations"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_TRUE(j["process_var"].contains("dtheta_rad2"));
  EXPECT_EQ(j["ml"]["standard_error_method"], "information");  // 145 stops: the full information
  for (const char* f : {"objective.png", "params.png", "trace.dat", "params.dat"})
    EXPECT_TRUE(std::filesystem::exists(dir / "plots" / f)) << f;
}

TEST(CliNoise, MlWithTheProcessNoiseGivenKeepsItAndNeedsItGiven) {
  TempDir dir;
  test::writeFile(dir / "scene.json", kScene);
  ASSERT_EQ(runCli("simulate -q --scene " + (dir / "scene.json").string() + " --out " +
                   (dir / "sim").string() + " --seed 6")
                .exit_code,
            0);
  const std::string inputs = " --observations " + (dir / "sim/observations.csv").string() +
                             " --odometry " + (dir / "sim/odometry.csv").string() +
                             " --method ml --fixed-process";
  // Without --init there is nothing to keep: an error, no output.
  auto r = runCli("noise-consistency -q" + inputs + " --out " + (dir / "a.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--init"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "a.json"));
  // The truth's process variances given (its sensor variances are only the start).
  r = runCli("noise-consistency -q" + inputs + " --init " +
             (dir / "sim/noise_truth.json").string() + " --out " + (dir / "b.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = readJson(dir / "b.json");
  EXPECT_FALSE(j["process_var_estimated"].get<bool>());
  EXPECT_DOUBLE_EQ(j["process_var"]["dx_m2"].get<double>(), 0.004);
  EXPECT_DOUBLE_EQ(j["process_var"]["dy_m2"].get<double>(), 0.004);
  EXPECT_DOUBLE_EQ(j["process_var"]["dtheta_rad2"].get<double>(), 0.0005);
  const double truth_var[2][2] = {{0.3, 0.4}, {0.5, 0.6}};
  for (int s = 0; s < 2; ++s) {
    const auto& e = j["sensors"][s];
    EXPECT_NEAR(e["range_var_m2"].get<double>(), truth_var[s][0],
                4 * e["range_var_se_m2"].get<double>());
    EXPECT_NEAR(e["bearing_var_rad2"].get<double>(), truth_var[s][1],
                4 * e["bearing_var_se_rad2"].get<double>());
  }
}

TEST(CliNoise, KlHillTraceNeverIncreasesAndTheSameSeedGivesTheSameResult) {
  TempDir dir;
  test::writeFile(dir / "scene.json", kScene);
  ASSERT_EQ(runCli("simulate -q --scene " + (dir / "scene.json").string() + " --out " +
                   (dir / "sim").string() + " --seed 5")
                .exit_code,
            0);
  nlohmann::json runs[3];
  for (int i = 0; i < 3; ++i) {
    const std::string out = (dir / ("kl" + std::to_string(i) + ".json")).string();
    const auto r =
        runCli("noise-consistency -q --observations " + (dir / "sim/observations.csv").string() +
               " --odometry " + (dir / "sim/odometry.csv").string() +
               " --method kl-hill --particles 8 --max-evaluations 12 --seed 2 --out " + out +
               (i == 2 ? " --record-time" : ""));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    runs[i] = readJson(out);
  }
  const auto& trace = runs[0]["objective_trace"];
  ASSERT_EQ(trace.size(), 12u);
  for (std::size_t i = 1; i < trace.size(); ++i)
    EXPECT_LE(trace[i].get<double>(), trace[i - 1].get<double>());
  EXPECT_EQ(runs[0]["status"], "not_converged");  // stopped by the evaluation cap
  EXPECT_EQ(runs[0], runs[1]);
  // --record-time adds the wall time and nothing else.
  EXPECT_FALSE(runs[0].contains("time_s"));
  ASSERT_TRUE(runs[2].contains("time_s"));
  EXPECT_GT(runs[2]["time_s"].get<double>(), 0.0);
  runs[2].erase("time_s");
  EXPECT_EQ(runs[0], runs[2]);
}

TEST(CliNoise, BadInputIsReportedWithFileLineAndColumnAndNothingIsWritten) {
  TempDir dir;
  test::writeFile(dir / "o.csv", "stop,sensor,landmark,range_m,bearing_rad\n0,0,1,2.0,x\n");
  test::writeFile(dir / "d.csv", "stop,dx_m,dy_m,dtheta_rad\n0,0,0,0\n");
  auto r = runCli("noise-consistency --observations " + (dir / "o.csv").string() + " --odometry " +
                  (dir / "d.csv").string() + " --out " + (dir / "r.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("line 2, column bearing_rad: `x` is not a number"), std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "r.json"));
  test::writeFile(dir / "o.csv", "stop,sensor,landmark,range_m,bearing_rad\n3,0,1,2.0,0.1\n");
  r = runCli("noise-consistency --observations " + (dir / "o.csv").string() + " --odometry " +
             (dir / "d.csv").string() + " --out " + (dir / "r.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("stop 3"), std::string::npos) << r.err;
  r = runCli("noise-consistency --observations " + (dir / "o.csv").string() + " --odometry " +
             (dir / "d.csv").string() + " --out " + (dir / "o.csv").string() + " --overwrite");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("is one of the inputs"), std::string::npos) << r.err;
}

TEST(CliNoise, LandmarksCsvOfTheBundledExampleConvertsWithItsStopPoses) {
  TempDir dir;
  test::writeFile(
      dir / "l.csv",
      "file,stop,landmark,bearing_rad,range_m,centre_x_m,centre_y_m,radius_m,n_points,rms_m\n"
      "scan_000000.pcd,0,1,0.46,1.68,1.5,0.75,0.12,20,0.004\n"
      "scan_000095.pcd,9,1,1.2,1.3,0.5,1.2,0.12,20,0.004\n");
  const auto r = runCli("landmarks-to-observations -q --landmarks " + (dir / "l.csv").string() +
                        " --sequence " + (test::sourceDir() / "data/example/scans").string() +
                        " --out " + (dir / "out").string() + " --range-to surface");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto obs = io::readObservations(dir / "out/observations.csv");
  ASSERT_EQ(obs.size(), 2u);
  EXPECT_NEAR(obs[1].range_m, 1.3 - 0.12, 1e-9);
  const auto odo = io::readOdometry(dir / "out/odometry.csv");
  ASSERT_EQ(odo.size(), 10u);  // the example has 10 stops 0.30 m apart along x
  for (std::size_t k = 1; k < odo.size(); ++k) EXPECT_NEAR(odo[k].dx_m, 0.30, 1e-5);
  test::writeFile(
      dir / "l.csv",
      "file,stop,landmark,bearing_rad,range_m,centre_x_m,centre_y_m,radius_m,n_points,rms_m\n"
      "scan_000000.pcd,10,1,0.46,1.68,1.5,0.75,0.12,20,0.004\n");
  const auto bad = runCli("landmarks-to-observations --landmarks " + (dir / "l.csv").string() +
                          " --sequence " + (test::sourceDir() / "data/example/scans").string() +
                          " --out " + (dir / "out2").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("is not a stop of the sequence"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace lidarcal
