// SPDX-License-Identifier: BSD-3-Clause
// The Slurm recipes of scripts/slurm/ submitted to a real single-node Slurm (slurm_cluster.hpp):
// a Monte Carlo study as an array of shards and a dependent merge, checked byte for byte against
// the study run in one process; a fleet as an array of `lidarcal run` tasks and a dependent fleet
// report, checked against the models the tasks wrote and against a run outside Slurm. Skipped,
// with the reason, where Slurm cannot start (no packages, not root); with
// LIDARCAL_REQUIRE_SLURM=1 (CI) a cluster that does not come up is a failure. Nothing is left
// running: the fixture ends the daemons and fails if any process of the cluster remains.

#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "calibration/fleet.hpp"
#include "io/model_io.hpp"
#include "slurm_cluster.hpp"

namespace lidarcal::test {
namespace {

class SlurmRecipes : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ =
        new fs::path(fs::temp_directory_path() / ("lidarcal-slurm-" + std::to_string(::getpid())));
    fs::remove_all(*dir_);
    cluster_ = new SlurmCluster;
    std::string why_not;
    if (!cluster_->start(*dir_ / "cluster", why_not)) *skip_ = "Slurm test skipped: " + why_not;
    ::setenv("LIDARCAL", LIDARCAL_EXE, 1);  // the binary the jobs run
  }
  static void TearDownTestSuite() {
    const std::vector<std::string> left = cluster_->stop();
    for (const auto& p : left) ADD_FAILURE() << "left running after the cluster stopped: " << p;
    delete cluster_;
    std::error_code ec;
    fs::remove_all(*dir_, ec);
    delete dir_;
  }
  void SetUp() override {
    if (skip_->empty()) return;
    const char* require = std::getenv("LIDARCAL_REQUIRE_SLURM");
    if (require && std::string(require) == "1" &&
        skip_->find("must run as root") == std::string::npos)
      FAIL() << *skip_;
    GTEST_SKIP() << *skip_;
  }

  /// Runs a submit script; returns the job ids it prints as NAME_job=ID, in order.
  static std::vector<std::string> submit(const std::string& script, const std::string& args) {
    std::string out;
    const int code =
        shell("bash " + (sourceDir() / "scripts" / "slurm" / script).string() + " " + args, &out);
    EXPECT_EQ(code, 0) << out;
    std::vector<std::string> ids;
    for (std::size_t at = out.find("_job="); at != std::string::npos;
         at = out.find("_job=", at + 1))
      ids.push_back(out.substr(at + 5, out.find('\n', at) - at - 5));
    return ids;
  }

  /// Waits (at most ten minutes) until the jobs have left the queue; returns each job's states
  /// (an array job lists one per task), e.g. "COMPLETED COMPLETED".
  static std::string waitForJobs(const std::vector<std::string>& ids) {
    std::string list;
    for (const auto& id : ids) list += (list.empty() ? "" : ",") + id;
    std::string queued;
    const bool done = waitFor(
        [&] { return shell("squeue -h -j " + list + " -o %i", &queued) == 0 && queued.empty(); },
        600.0);
    EXPECT_TRUE(done) << "still queued: " << queued << cluster_->logs();
    std::string states;
    for (const auto& id : ids) {
      std::string show;
      shell("scontrol -o show job " + id, &show);
      for (std::size_t at = show.find("JobState="); at != std::string::npos;
           at = show.find("JobState=", at + 1))
        states += show.substr(at + 9, show.find(' ', at) - at - 9) + " ";
    }
    return states;
  }

  static bool allCompleted(const std::string& states) {
    return !states.empty() && states.find_first_not_of("COMPLETED ") == std::string::npos;
  }

  static fs::path* dir_;
  static SlurmCluster* cluster_;
  static std::string* skip_;
};
fs::path* SlurmRecipes::dir_ = nullptr;
SlurmCluster* SlurmRecipes::cluster_ = nullptr;
std::string* SlurmRecipes::skip_ = new std::string;

TEST_F(SlurmRecipes, StudyShardsAndTheirMergeGiveTheSingleProcessBytes) {
  const std::string study =
      "--quick --study fig9 --trials 4 --joint-trials 1 --stops 8 --step 0.3 --scans-per-stop 3 "
      "--seed 5";
  const fs::path out = *dir_ / "study";
  const auto ids = submit("submit-montecarlo.sh", "3 " + out.string() + " " + study);
  ASSERT_EQ(ids.size(), 2u);
  const std::string states = waitForJobs(ids);
  ASSERT_TRUE(allCompleted(states))
      << states << "\n"
      << readFile(out / "logs" / "merge.out") << readFile(out / "logs" / "shard-0.out");
  for (int k = 1; k <= 3; ++k)
    EXPECT_TRUE(fs::exists(out / "shards" / std::to_string(k) / "shard.json")) << k;
  const auto whole = runCli("-q montecarlo " + study + " --out " + (*dir_ / "whole").string());
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  expectSameFiles(snapshot(*dir_ / "whole"), snapshot(out / "study"));
}

TEST_F(SlurmRecipes, FleetTasksAndTheirReportAgreeWithThePerRecordingModels) {
  // Four sensors recorded on two dates: eight `lidarcal run` tasks, then the report.
  const nlohmann::json base =
      nlohmann::json::parse(readFile(sourceDir() / "data/scenes/paper_field.json"));
  const fs::path fleet = *dir_ / "fleet";
  fs::create_directories(fleet / "recordings");
  std::string list = "sensor,date,input\n";
  const std::vector<std::string> dates = {"2024-06-03", "2024-06-10"};
  for (int i = 0; i < 4; ++i)
    for (std::size_t w = 0; w < dates.size(); ++w) {
      nlohmann::json scene = base;
      scene["sensor"]["name"] = "agv" + std::to_string(i);
      scene["path"]["scans_per_stop"] = 3;
      const std::string tag = "agv" + std::to_string(i) + "_" + dates[w];
      writeFile(fleet / (tag + ".json"), scene.dump());
      const auto sim = runCli("-q simulate --scene " + (fleet / (tag + ".json")).string() + " -o " +
                              (fleet / "recordings" / tag).string() + " --seed " +
                              std::to_string(10 * i + static_cast<int>(w) + 1));
      ASSERT_EQ(sim.exit_code, 0) << sim.err;
      list += "agv" + std::to_string(i) + "," + dates[w] + ",recordings/" + tag + "/scans\n";
    }
  writeFile(fleet / "list.csv", list);
  const fs::path out = fleet / "out";
  const auto ids = submit("submit-fleet.sh", (fleet / "list.csv").string() + " " + out.string());
  ASSERT_EQ(ids.size(), 2u);
  const std::string states = waitForJobs(ids);
  ASSERT_TRUE(allCompleted(states))
      << states << "\n"
      << readFile(out / "logs" / "summary.out") << readFile(out / "logs" / "run-0.out");

  const nlohmann::json report = nlohmann::json::parse(readFile(out / "report" / "fleet.json"));
  ASSERT_EQ(report["sensors"].size(), 4u);
  const auto distances = report["settings"]["distances_m"].get<std::vector<double>>();
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    const nlohmann::json& row = report["sensors"][static_cast<std::size_t>(i)];
    EXPECT_EQ(row["sensor"], "agv" + std::to_string(i));
    EXPECT_EQ(row["date"], dates[1]);
    const fs::path run = out / "runs" / ("agv" + std::to_string(i));
    EXPECT_EQ(row["previous"]["model"], (run / dates[0] / "model.json").string());
    EXPECT_TRUE(row["moved"]["tested"].get<bool>()) << row["moved"].dump();
    const auto expected =
        calibration::biasAt(io::readModel(run / dates[1] / "model.json"), distances);
    for (std::size_t j = 0; j < distances.size(); ++j) {
      EXPECT_DOUBLE_EQ(row["bias"][j]["bias_m"].get<double>(), expected[j].bias_m);
      EXPECT_DOUBLE_EQ(row["bias"][j]["se_m"].get<double>(), expected[j].se_m);
    }
  }
  // A task's model is the one `lidarcal run` writes outside Slurm.
  const auto local =
      runCli("-q run " + (fleet / "recordings" / ("agv2_" + dates[1]) / "scans").string() + " -o " +
             (fleet / "local").string());
  ASSERT_EQ(local.exit_code, 0) << local.err;
  EXPECT_EQ(readFile(fleet / "local" / "model.json"),
            readFile(out / "runs" / "agv2" / dates[1] / "model.json"));
  EXPECT_TRUE(fs::exists(out / "fleet.csv"));
  EXPECT_TRUE(fs::exists(out / "report" / "fleet.md"));
}

}  // namespace
}  // namespace lidarcal::test
