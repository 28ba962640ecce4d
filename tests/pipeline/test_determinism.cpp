// SPDX-License-Identifier: BSD-3-Clause
// Same input and seed give byte-identical output, for every command that writes files. A
// command with a --threads option (its --help says so) is run with --threads 1 and --threads 2;
// the others are run twice. Both runs write to the same path (the first result is moved aside)
// because reports quote their output path. To cover a new command, add one row to kCommands.

#include <gtest/gtest.h>

#include "bad_input_util.hpp"
#include "io/import_test_util.hpp"

namespace lidarcal {
namespace {

using namespace test;

struct WritingCommand {
  const char* name;
  std::string args;  ///< placeholders: {IN} inputs (below), {OUT} output path, {SHARED} shared data
  /// relative to {SHARED}: skip when absent (empty: always runs)
  std::string skip_unless_exists = {};
};

/// Inputs under IN: sim/ (paper field, 10 stops x 2 scans, with truth), model.json (calibrated
/// on it), corrected/ (its correction), a CSV, a CARMEN and a YDLIDAR recording.
const fs::path& inputs() {
  static const fs::path dir = cachedFixture("determinism-2", [](const fs::path& d) {
    const fs::path in = d;
    const std::string scene = (sourceDir() / "data/scenes/paper_field.json").string();
    EXPECT_EQ(runCli("simulate -q --scene " + scene + " --out " + (in / "sim").string() +
                     " --scans-per-stop 2 --seed 9")
                  .exit_code,
              0);
    EXPECT_EQ(runCli("calibrate -q " + (in / "sim/scans").string() + " --out " +
                     (in / "model.json").string())
                  .exit_code,
              0);
    EXPECT_EQ(runCli("correct -q " + (in / "sim/scans").string() + " --model " +
                     (in / "model.json").string() + " --out " + (in / "corrected").string())
                  .exit_code,
              0);
    EXPECT_EQ(
        runCli("detect -q " + (in / "sim/scans").string() + " --out " + (in / "detected").string())
            .exit_code,
        0);
    EXPECT_EQ(
        runCli("simulate -q --scene " + (sourceDir() / "data/scenes/noise_exp3.json").string() +
               " --out " + (in / "noise").string() + " --seed 2")
            .exit_code,
        0);
    std::string csv = "scan,x_m,y_m,yaw_rad,angle_rad,range_m,intensity\n", carmen, dat;
    for (int s = 0; s < 6; ++s) {
      std::string flaser = "FLASER 181", ranges;
      for (int b = 0; b < 181; ++b) {
        const double r = 1.0 + 0.01 * b + 0.1 * s;
        csv += std::to_string(s) + "," + std::to_string(0.1 * s) + ",0,0," +
               std::to_string(0.0174533 * b) + "," + std::to_string(r) + ",7\n";
        flaser += " " + std::to_string(r);
        ranges += "," + std::to_string(r);
      }
      carmen += flaser + " " + std::to_string(0.1 * s) + " 0 0 0 0 0 1.5 host 1.5\n";
      dat += "100,1,0.1" + ranges + "\n";
    }
    writeFile(in / "rec.csv", csv);
    writeGzip(in / "rec.log.gz", carmen);
    writeFile(in / "rec.dat", dat);
  });
  return dir;
}

const std::vector<WritingCommand> kCommands = {
    {"simulate",
     "simulate -q --scene {SRC}/data/scenes/field_clutter.json --out {OUT} --stops 3 "
     "--scans-per-stop 2 --seed 5"},
    {"import_csv", "import -q --from csv {IN}/rec.csv --out {OUT}"},
    {"import_carmen", "import -q --from carmen {IN}/rec.log.gz --out {OUT}"},
    {"import_ydlidar", "import -q --from ydlidar {IN}/rec.dat --out {OUT}"},
    {"import_rosbag",
     "import -q --from rosbag1 {SHARED}/rplidar_a2_room/rplidar_1.bag --max-scans 50 --out {OUT}",
     "rplidar_a2_room/rplidar_1.bag"},
    {"detect", "detect -q {IN}/sim/scans --out {OUT}"},
    {"detect_estimated_radius",
     "detect -q {IN}/sim/scans --estimate-radius --truth {IN}/sim/truth.json --out {OUT}"},
    {"calibrate", "calibrate -q {IN}/sim/scans --out {OUT}"},
    {"calibrate_report",
     "calibrate -q {IN}/sim/scans --method closed-form --report {OUT}.report --out {OUT}"},
    {"calibrate_oracle", "calibrate -q {IN}/sim/scans --truth {IN}/sim/truth.json --out {OUT}"},
    {"correct", "correct -q {IN}/sim/scans --model {IN}/model.json --out {OUT}"},
    {"correct_ml",
     "correct -q {IN}/sim/scans --model {IN}/model.json --inversion ml --ascii --out {OUT}"},
    {"run", "run -q {IN}/sim/scans --out {OUT}"},
    {"evaluate", "evaluate {IN}/corrected --truth {IN}/sim/truth.json --out {OUT}"},
    {"simulate_observations",
     "simulate -q --scene {SRC}/data/scenes/noise_exp12.json --out {OUT} --seed 5"},
    {"landmarks_to_observations",
     "landmarks-to-observations --landmarks {IN}/detected/landmarks.csv --sequence {IN}/sim/scans "
     "--out {OUT}"},
    {"noise_consistency_ml",
     "noise-consistency -q --observations {IN}/noise/observations.csv --odometry "
     "{IN}/noise/odometry.csv --method ml "
     "--out {OUT}"},
    {"noise_consistency_kl_hill",
     "noise-consistency -q --observations {IN}/noise/observations.csv --odometry "
     "{IN}/noise/odometry.csv --method kl-hill "
     "--particles 4 --max-evaluations 6 --seed 3 --out {OUT}"},
    {"diagnose",
     "diagnose -q {IN}/sim/scans --replicas 5 --folds 2 --truth {IN}/sim/truth.json --out {OUT}"},
    {"montecarlo", "montecarlo -q --study fig8 --quick --trials 4 --joint-trials 2 --out {OUT}"},
};

class Determinism : public ::testing::TestWithParam<WritingCommand> {};

/// Everything a run wrote: the files at OUT (a file or a directory) and at OUT.report.
std::map<std::string, std::string> written(const fs::path& out) {
  std::map<std::string, std::string> files;
  for (const fs::path& p : {out, fs::path(out.string() + ".report")}) {
    if (fs::is_directory(p))
      for (auto& [name, bytes] : snapshot(p)) files[p.filename().string() + "/" + name] = bytes;
    else if (fs::exists(p))
      files[p.filename().string()] = readFile(p);
  }
  return files;
}

TEST_P(Determinism, SameInputGivesTheSameBytes) {
  const WritingCommand& c = GetParam();
  if (!c.skip_unless_exists.empty() && !fs::exists(sharedData() / c.skip_unless_exists))
    GTEST_SKIP() << "shared data absent: " << c.skip_unless_exists;
  TempDir dir;
  const fs::path out = dir / "out";
  std::string args = replaceAll(c.args, "{IN}", inputs().string());
  args = replaceAll(args, "{SRC}", sourceDir().string());
  args = replaceAll(args, "{SHARED}", sharedData().string());
  args = replaceAll(args, "{OUT}", out.string());
  const std::string command = args.substr(0, args.find(' '));
  const bool threads = runCli(command + " --help").out.find("--threads") != std::string::npos;
  std::vector<std::map<std::string, std::string>> results;
  for (int run = 1; run <= 2; ++run) {
    const std::string full = args + (threads ? " --threads " + std::to_string(run) : "");
    const CliResult r = runCli(full);
    ASSERT_EQ(r.exit_code, 0) << full << "\n" << r.err;
    results.push_back(written(out));
    ASSERT_FALSE(results.back().empty()) << "wrote nothing: " << full;
    for (const fs::path& p : {out, fs::path(out.string() + ".report")}) fs::remove_all(p);
  }
  ASSERT_EQ(results[0].size(), results[1].size());
  for (const auto& [name, bytes] : results[0]) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(results[1].count(name));
    EXPECT_TRUE(results[1].at(name) == bytes)
        << "differs between runs" << (threads ? " (1 and 2 threads)" : "");
  }
}

INSTANTIATE_TEST_SUITE_P(EveryWritingCommand, Determinism, ::testing::ValuesIn(kCommands),
                         [](const ::testing::TestParamInfo<WritingCommand>& p) {
                           return std::string(p.param.name);
                         });

}  // namespace
}  // namespace lidarcal
