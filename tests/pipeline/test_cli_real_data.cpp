// SPDX-License-Identifier: BSD-3-Clause
// Every recording in ../shared/data goes through `calibrate` and `run` to a result (exit 0, with
// standard errors) or a reasoned refusal (exit 3 saying what is missing and what to record):
// never an internal error. Skipped when ../shared/data is absent.

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

struct Recording {
  std::string name;     ///< test name
  std::string inputs;   ///< files under ../shared/data, space-separated
  std::string import;   ///< import options
  bool rosbag = false;  ///< needs the ROS1 reader
};

void PrintTo(const Recording& r, std::ostream* os) { *os << r.name; }

class RealRecording : public ::testing::TestWithParam<Recording> {};

TEST_P(RealRecording, CalibratesOrRefusesWithAReason) {
  const Recording& rec = GetParam();
  std::string inputs;
  for (std::size_t start = 0; start < rec.inputs.size();) {
    const std::size_t end = std::min(rec.inputs.find(' ', start), rec.inputs.size());
    const fs::path p = test::sharedData() / rec.inputs.substr(start, end - start);
    if (!fs::exists(p)) GTEST_SKIP() << p << " is absent";
    inputs += " " + p.string();
    start = end + 1;
  }
  TempDir dir;
  const auto imp =
      runCli("import -q" + inputs + " " + rec.import + " --out " + (dir / "seq").string());
  if (rec.rosbag && imp.exit_code == 2 && imp.err.find("ROS1") != std::string::npos)
    GTEST_SKIP() << "no ROS1 reader in this build";
  ASSERT_EQ(imp.exit_code, 0) << imp.err;
  for (const std::string command : {"calibrate", "run"}) {
    SCOPED_TRACE(command);
    const fs::path out = dir / (command + "-out");
    const auto r = runCli(
        command + " -q " + (dir / "seq").string() + " --out " +
        (command == std::string("calibrate") ? (dir / "model.json").string() : out.string()));
    ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 3) << "exit " << r.exit_code << ": " << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
    if (r.exit_code == 3) {
      // What is missing and what to do about it.
      EXPECT_TRUE(r.err.find("record") != std::string::npos ||
                  r.err.find("give") != std::string::npos)
          << r.err;
      continue;
    }
    const fs::path model =
        command == std::string("calibrate") ? dir / "model.json" : out / "model.json";
    const auto m = nlohmann::json::parse(test::readFile(model));
    EXPECT_EQ(m["bias"]["standard_error"].size(), m["bias"]["alpha"].size())
        << "every coefficient with its error";
    EXPECT_TRUE(m.contains("fitted_range"));
    EXPECT_NE(r.out.find("+-"), std::string::npos) << "standard errors on stdout:\n" << r.out;
    // A model given exit 0 is one `correct` takes (positive distances, a rising bias).
    const auto c = runCli("correct -q " + (dir / "seq").string() + " --model " + model.string() +
                          " --out " + (dir / (command + "-corrected")).string());
    EXPECT_EQ(c.exit_code, 0) << c.err;
  }
}

const std::string kHokuyo = "hokuyo_ust30lx_reflector/";

INSTANTIATE_TEST_SUITE_P(
    SharedData, RealRecording,
    ::testing::Values(
        Recording{"rplidar_a2_room", "rplidar_a2_room/rplidar_1.bag", "--from rosbag1", true},
        Recording{"ydlidar_19_38_28", "ydlidar_x4/2019-05-03-19-38-28.dat", "--from ydlidar"},
        Recording{"ydlidar_19_39_14", "ydlidar_x4/2019-05-03-19-39-14.dat", "--from ydlidar"},
        Recording{"ydlidar_19_42_50", "ydlidar_x4/2019-05-03-19-42-50.dat", "--from ydlidar"},
        Recording{"ydlidar_19_44_15", "ydlidar_x4/2019-05-03-19-44-15.dat", "--from ydlidar"},
        Recording{"carmen_intel", "carmen/intel-corrected.log.gz", "--from carmen"},
        Recording{"carmen_csail", "carmen/csail-corrected.log.gz", "--from carmen"},
        // 4791 poses: every third scan keeps the test short; the whole log calibrates too
        // (docs/results/real-sensors.md).
        Recording{"carmen_freiburg_079", "carmen/freiburg-079-corrected.log.gz",
                  "--from carmen --every 3"},
        Recording{"carmen_freiburg_campus", "carmen/freiburg-campus-corrected.log.gz",
                  "--from carmen"},
        Recording{"hokuyo_range_sweep_one_bag", kHokuyo + "range_sweep/bs_exp_1041.bag",
                  "--from rosbag1", true},
        Recording{"hokuyo_range_sweep_stops",
                  kHokuyo + "range_sweep/bs_exp_540.bag " + kHokuyo +
                      "range_sweep/bs_exp_1041.bag " + kHokuyo + "range_sweep/bs_exp_1550.bag " +
                      kHokuyo + "range_sweep/bs_exp_2050.bag",
                  "--from rosbag1 --stop-per-input --every 10", true},
        Recording{"hokuyo_reference_scenes",
                  kHokuyo + "reference_scenes/ref_505.bag " + kHokuyo +
                      "reference_scenes/ref_707.bag " + kHokuyo + "reference_scenes/ref_909.bag " +
                      kHokuyo + "reference_scenes/ref_1111.bag",
                  "--from rosbag1 --stop-per-input --every 10", true},
        Recording{"hokuyo_agv_front",
                  kHokuyo + "agv_two_lidars/obs2.bag " + kHokuyo + "agv_two_lidars/obs3.bag " +
                      kHokuyo + "agv_two_lidars/obs4.bag",
                  "--from rosbag1 --topic /scan_front --stop-per-input --every 5", true},
        Recording{"hokuyo_agv_back",
                  kHokuyo + "agv_two_lidars/obs5.bag " + kHokuyo + "agv_two_lidars/obs6.bag " +
                      kHokuyo + "agv_two_lidars/obs7.bag",
                  "--from rosbag1 --topic /scan_back --stop-per-input --every 5", true}),
    [](const ::testing::TestParamInfo<Recording>& p) { return p.param.name; });

}  // namespace
}  // namespace lidarcal
