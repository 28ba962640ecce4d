// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal montecarlo --shard K/N` and `lidarcal montecarlo-merge` end to end: the merged
// directory holds the bytes of the study run at once (CSV, summaries, gnuplot scripts, PNGs),
// whatever the number of shards, their order and their thread counts; shards of another study,
// seed, trial count or slice count, a slice given twice or missing, and a damaged trials file are
// refused with exit 2, naming the file and the field, and nothing is written.

#include <string>

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace lidarcal {
namespace {

using test::runCli;
using test::TempDir;
namespace fs = std::filesystem;

/// A small, fast study of the quick grid: 8 stops, 3 scans per stop, 4 trials, 1 with the joint
/// refinement.
const std::string kSmall =
    "montecarlo -q --quick --stops 8 --step 0.3 --scans-per-stop 3 --joint-trials 1";

std::string study(const std::string& figure, int trials = 4, int seed = 5) {
  return kSmall + " --study " + figure + " --trials " + std::to_string(trials) + " --seed " +
         std::to_string(seed);
}

/// Runs shards 1..n of `args` into dir/<prefix>K; returns the directories as one argument string.
std::string runShards(const TempDir& dir, const std::string& args, int n,
                      const std::string& prefix) {
  std::string dirs;
  for (int k = n; k >= 1; --k) {  // any order: the last first
    const std::string out = (dir / (prefix + std::to_string(k))).string();
    const auto r = runCli(args + " --threads " + std::to_string(1 + k % 2) + " --shard " +
                          std::to_string(k) + "/" + std::to_string(n) + " --out " + out);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    dirs += " " + out;
  }
  return dirs;
}

class CliMontecarloShards : public ::testing::TestWithParam<std::string> {};

TEST_P(CliMontecarloShards, MergedShardsAreByteIdenticalToTheWholeStudy) {
  TempDir dir;
  const std::string args = study(GetParam());
  const fs::path whole = dir / "whole";
  const auto r = runCli(args + " --threads 2 --out " + whole.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto expected = test::snapshot(whole);
  ASSERT_TRUE(expected.count(GetParam() + ".csv"));
  ASSERT_TRUE(expected.count("summary.md"));
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    ASSERT_TRUE(expected.count(GetParam() + ".png"));
  }
  for (int shards : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(shards) + " shard(s)");
    const std::string prefix = "s" + std::to_string(shards) + "_";
    const std::string dirs = runShards(dir, args, shards, prefix);
    const fs::path merged = dir / ("merged" + std::to_string(shards));
    const auto m = runCli("montecarlo-merge" + dirs + " --out " + merged.string());
    ASSERT_EQ(m.exit_code, 0) << m.err;
    test::expectSameFiles(expected, test::snapshot(merged));
    // A shard holds the trials' results only, not the figures.
    EXPECT_EQ(test::snapshot(dir / (prefix + "1")).size(), 2u);
  }
}

INSTANTIATE_TEST_SUITE_P(Figures, CliMontecarloShards, ::testing::Values("fig7", "fig9"));

/// Runs the merge and checks it fails with exit 2, wrote nothing, and says each of `words`.
void expectRefused(const std::string& dirs, const fs::path& out,
                   const std::vector<std::string>& words) {
  const auto r = runCli("montecarlo-merge" + dirs + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  for (const auto& w : words)
    EXPECT_NE(r.err.find(w), std::string::npos) << "missing '" << w << "' in: " << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliMontecarloShardsRefused, MismatchedMissingDuplicateOrDamagedShards) {
  TempDir dir;
  const std::string args = study("fig9", 3);
  runShards(dir, args, 3, "a");
  const std::string a1 = " " + (dir / "a1").string(), a2 = " " + (dir / "a2").string(),
                    a3 = " " + (dir / "a3").string();
  const fs::path out = dir / "out";
  // Slice 2 of another seed, trial count, study, or cut into another number of slices.
  ASSERT_EQ(runCli(study("fig9", 3, 6) + " --shard 2/3 --out " + (dir / "seed").string()).exit_code,
            0);
  expectRefused(a1 + " " + (dir / "seed").string() + a3, out,
                {"seed/shard.json", "study.seed", "is 6", "has 5"});
  ASSERT_EQ(runCli(study("fig9", 4) + " --shard 2/3 --out " + (dir / "trials").string()).exit_code,
            0);
  expectRefused(a1 + " " + (dir / "trials").string() + a3, out,
                {"trials/shard.json", "study.trials"});
  ASSERT_EQ(runCli(study("fig7", 3) + " --shard 2/3 --out " + (dir / "fig7").string()).exit_code,
            0);
  expectRefused(a1 + " " + (dir / "fig7").string() + a3, out,
                {"fig7/shard.json", "study.study", "\"fig7\""});
  ASSERT_EQ(runCli(args + " --shard 2/4 --out " + (dir / "four").string()).exit_code, 0);
  expectRefused(a1 + " " + (dir / "four").string() + a3, out,
                {"four/shard.json", "shards", "is 4"});
  // A slice missing, or given twice.
  expectRefused(a1 + a3, out, {"missing slice(s) 2/3"});
  expectRefused(a1 + a2 + a3 + a2, out, {"a2/shard.json", "slice 2/3 is given twice"});
  // A directory that is not a shard.
  fs::create_directories(dir / "empty");
  expectRefused(a1 + " " + (dir / "empty").string() + a3, out,
                {"empty: shard.json", "not a shard directory"});
  // A trials file cut short, or with a damaged number.
  const std::string records = test::readFile(dir / "a2" / "trials.csv");
  test::writeFile(dir / "a2" / "trials.csv",
                  records.substr(0, records.find('\n', records.size() / 2) + 1));
  expectRefused(a1 + a2 + a3, out, {"a2/trials.csv", "records", "of the"});
  test::writeFile(dir / "a2" / "trials.csv",
                  records.substr(0, records.find('\n') + 1) + "0,0,zwei" +
                      records.substr(records.find('\n', records.find('\n') + 1)));
  expectRefused(a1 + a2 + a3, out, {"a2/trials.csv", "line 2", "column 3 (detected_landmarks)"});
  // The slices whole again: merged.
  test::writeFile(dir / "a2" / "trials.csv", records);
  EXPECT_EQ(runCli("montecarlo-merge" + a1 + a2 + a3 + " --out " + out.string()).exit_code, 0);
}

TEST(CliMontecarloShardsRefused, BadShardOptions) {
  TempDir dir;
  const std::string out = (dir / "o").string();
  for (const char* bad : {"0/3", "4/3", "3", "1/0", "a/b", "1/3/5", "-1/3"}) {
    SCOPED_TRACE(bad);
    const auto r = runCli(study("fig9") + " --shard " + bad + " --out " + out);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--shard"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace lidarcal
