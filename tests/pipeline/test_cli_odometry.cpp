// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal odometry` end to end: simulated tuples with a known truth, the table and
// OUT.json, the subset scatter, refusals with their exit codes, and the shared recordings.

#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "odometry/simulated_samples.hpp"
#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;

/// Writes `samples` as odometry tuples, two objects on the first line as in the shared data.
void writeTuples(const std::filesystem::path& file, const std::vector<OdometrySample>& samples) {
  std::string text;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const OdometrySample& s = samples[i];
    const nlohmann::json j = {{"T", s.duration_s},
                              {"phi_l", s.left_wheel_rad_s},
                              {"phi_r", s.right_wheel_rad_s},
                              {"sm", {s.scan_match_x_m, s.scan_match_y_m, s.scan_match_theta_rad}}};
    text += j.dump() + (i == 0 ? "" : "\n");
  }
  test::writeFile(file, text);
}

odometry::SimulationSettings drive() {
  odometry::SimulationSettings s;
  s.samples = 1500;
  s.outlier_fraction = 0.02;
  return s;
}

TEST(CliOdometry, CalibratesSimulatedTuplesAndWritesTheResult) {
  TempDir dir;
  const odometry::SimulationSettings settings = drive();
  writeTuples(dir / "drive.tuple", odometry::simulateSamples(settings));
  const auto r =
      runCli("odometry " + (dir / "drive.tuple").string() + " -o " + (dir / "out.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| left wheel radius r_L |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| laser heading l_theta |"), std::string::npos);
  EXPECT_NE(r.out.find("from 1500 samples"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(test::readFile(dir / "out.json"));
  EXPECT_EQ(j["format"], "lidarcal-odometry/1");
  EXPECT_EQ(j["status"]["code"], "ok");
  EXPECT_EQ(j["samples"]["total"], 1500);
  EXPECT_EQ(j["covariance"]["order"][2], "axle_m");
  const std::vector<double> truth = {settings.truth.left_radius_m, settings.truth.right_radius_m,
                                     settings.truth.axle_m,        settings.truth.laser_x_m,
                                     settings.truth.laser_y_m,     settings.truth.laser_theta_rad};
  for (int k = 0; k < 6; ++k) {
    const std::string name = j["covariance"]["order"][k];
    const double value = j["estimate"][name], error = j["standard_error"][name];
    EXPECT_NEAR(error * error, j["covariance"]["matrix"][k][k].get<double>(),
                1e-12 * error * error);
    EXPECT_LT(std::abs(value - truth[k]), 4.0 * error) << name;
  }
}

TEST(CliOdometry, TheSubsetScatterIsReportedAndTheOutputIsDeterministic) {
  TempDir dir;
  writeTuples(dir / "drive.tuple", odometry::simulateSamples(drive()));
  std::string first;
  for (const char* name : {"a.json", "b.json"}) {
    const auto r = runCli("odometry " + (dir / "drive.tuple").string() + " -o " +
                          (dir / name).string() + " --subsets 3");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("scatter over 3 consecutive subsets"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| spread / stated |"), std::string::npos) << r.out;
  }
  EXPECT_EQ(test::readFile(dir / "a.json"), test::readFile(dir / "b.json"));
  const nlohmann::json j = nlohmann::json::parse(test::readFile(dir / "a.json"));
  EXPECT_EQ(j["subsets"]["count"], 3);
  EXPECT_EQ(j["subsets"]["each"].size(), 3u);
  EXPECT_EQ(j["subsets"]["each"][1]["first_sample"], 500);
  EXPECT_GT(j["subsets"]["parameters"]["axle_m"]["spread"].get<double>(), 0.0);
}

TEST(CliOdometry, DataThatCannotDetermineTheParametersExitsThreeSayingWhatToRecord) {
  TempDir dir;
  odometry::SimulationSettings straight;
  straight.mix = {true, false, false, false};
  writeTuples(dir / "straight.tuple", odometry::simulateSamples(straight));
  const auto r = runCli("odometry " + (dir / "straight.tuple").string() + " -o " +
                        (dir / "out.json").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("degenerate_motion"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("turns in both directions"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.json"));
}

TEST(CliOdometry, BadInputExitsTwoNamingTheObjectAndField) {
  TempDir dir;
  test::writeFile(dir / "bad.tuple", "{\"T\": 0.8, \"phi_l\": 0.1, \"sm\": [0, 0, 0]}\n");
  const auto r =
      runCli("odometry " + (dir / "bad.tuple").string() + " -o " + (dir / "out.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.tuple: object 1 (line 1), field phi_r: is missing"), std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.json"));
  // An existing output is kept unless --overwrite.
  writeTuples(dir / "drive.tuple", odometry::simulateSamples(drive()));
  test::writeFile(dir / "out.json", "keep");
  const auto kept =
      runCli("odometry " + (dir / "drive.tuple").string() + " -o " + (dir / "out.json").string());
  EXPECT_EQ(kept.exit_code, 2);
  EXPECT_EQ(test::readFile(dir / "out.json"), "keep");
  EXPECT_EQ(runCli("odometry " + (dir / "drive.tuple").string() + " -o " +
                   (dir / "out.json").string() + " --overwrite")
                .exit_code,
            0);
}

TEST(CliOdometry, HelpNamesTheOptionsAndThePaper) {
  const auto r = runCli("odometry --help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* part :
       {"TUPLES", "--out", "--subsets", "--rounds", "--percentile", "Censi et al. 2013"})
    EXPECT_NE(r.out.find(part), std::string::npos) << part;
}

TEST(CliOdometry, TheSharedRecordingsCalibrate) {
  // Both were recorded in phases (l90: turning in place, then pivoting about one wheel, then
  // the other): consecutive thirds of l90 hold one kind of motion each, interleaved subsets
  // keep the mix.
  const auto dir = test::sharedData() / "censi_odometry";
  if (!std::filesystem::exists(dir / "l90.tuple")) GTEST_SKIP() << "no " << dir.string();
  TempDir out;
  for (const char* name : {"l90", "lmov"}) {
    SCOPED_TRACE(name);
    const std::string tuples = (dir / (std::string(name) + ".tuple")).string();
    const auto json = out / (std::string(name) + ".json");
    const auto r = runCli("odometry " + tuples + " -o " + json.string() +
                          " --subsets 5 --subset-split interleaved");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(test::readFile(json));
    EXPECT_EQ(j["samples"]["total"], std::string(name) == "l90" ? 3295 : 4345);
    EXPECT_EQ(j["subsets"]["split"], "interleaved");
    EXPECT_EQ(j["subsets"]["ok"], 5);
  }
  const auto thirds = runCli("odometry " + (dir / "l90.tuple").string() + " -o " +
                             (out / "thirds.json").string() + " --subsets 3");
  EXPECT_EQ(thirds.exit_code, 0) << thirds.err;
  EXPECT_NE(thirds.out.find("subset 2: degenerate_motion"), std::string::npos) << thirds.out;
}

/// The `lidarcal odometry` command lines of a Markdown file (continuation lines joined), with
/// the binary, the shared data and /tmp/ replaced for this build and `out`.
std::vector<std::string> documentedCommands(const std::filesystem::path& doc,
                                            const std::filesystem::path& out) {
  std::vector<std::string> commands;
  std::istringstream in(test::readFile(doc));
  std::string line;
  const std::string prefix = "build/pipeline/lidarcal odometry ";
  while (std::getline(in, line)) {
    if (line.rfind(prefix, 0) != 0) continue;
    std::string command = line;
    while (!command.empty() && command.back() == '\\' && std::getline(in, line))
      command = command.substr(0, command.size() - 1) + line;
    command = command.substr(command.find("odometry "));
    for (const auto& [from, to] :
         {std::pair<std::string, std::string>{"../shared/data", test::sharedData().string()},
          {"/tmp/", out.string() + "/"}})
      for (std::size_t at = command.find(from); at != std::string::npos;
           at = command.find(from, at + to.size()))
        command.replace(at, from.size(), to);
    commands.push_back(command);
  }
  return commands;
}

TEST(CliOdometry, TheDocumentedCommandsRun) {
  if (!std::filesystem::exists(test::sharedData() / "censi_odometry"))
    GTEST_SKIP() << "no shared data";
  TempDir out;
  std::size_t count = 0;
  for (const char* doc : {"README.md", "docs/COMMANDS.md", "docs/results/odometry.md"})
    for (const std::string& command : documentedCommands(test::sourceDir() / doc, out.path())) {
      SCOPED_TRACE(std::string(doc) + ": " + command);
      const auto r = runCli(command);
      EXPECT_EQ(r.exit_code, 0) << r.err;
      EXPECT_NE(r.out.find("| laser heading l_theta |"), std::string::npos);
      ++count;
    }
  EXPECT_GE(count, 6u);
}

}  // namespace
}  // namespace lidarcal
