// SPDX-License-Identifier: BSD-3-Clause
// Shards of a Monte Carlo study: the slices hold every trial exactly once and share the slow
// (joint refinement) trials evenly; a trial's record reads back bit for bit, and a damaged one is
// refused naming its column; the study run slice by slice and put back together from the records
// gives the files of the study run at once.

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "studies/runner.hpp"
#include "studies/study.hpp"
#include "studies/trial_record.hpp"

namespace lidarcal::studies {
namespace {

RunOptions options(std::size_t trials, std::size_t joint_trials, std::size_t shard,
                   std::size_t shards) {
  RunOptions o;
  o.trials = trials;
  o.joint_trials = joint_trials;
  o.shard_index = shard;
  o.shard_count = shards;
  return o;
}

TEST(MontecarloShards, SlicesHoldEveryTrialOnceAndShareTheJointTrialsAndEveryCellEvenly) {
  for (const auto& [cells, trials, joint] :
       {std::tuple<std::size_t, std::size_t, std::size_t>{1, 1, 1},
        {3, 6, 2},
        {18, 6, 2},
        {5, 40, 0},
        {24, 10, 10},
        {7, 13, 4}})
    for (std::size_t shards : {1, 2, 3, 4, 7, 64}) {
      SCOPED_TRACE("cells " + std::to_string(cells) + ", trials " + std::to_string(trials) +
                   ", joint " + std::to_string(joint) + ", shards " + std::to_string(shards));
      std::map<std::pair<std::size_t, std::size_t>, int> seen;
      std::size_t fewest_joint = SIZE_MAX, most_joint = 0, fewest = SIZE_MAX, most = 0;
      std::vector<std::size_t> fewest_of_cell(cells, SIZE_MAX), most_of_cell(cells, 0);
      for (std::size_t k = 0; k < shards; ++k) {
        const auto slice = shardTrials(cells, options(trials, joint, k, shards));
        std::size_t with_joint = 0;
        std::vector<std::size_t> of_cell(cells, 0);
        for (const TrialIndex& t : slice) {
          ASSERT_LT(t.cell, cells);
          ASSERT_LT(t.trial, trials);
          ++seen[{t.cell, t.trial}];
          if (t.trial < joint) ++with_joint;
          ++of_cell[t.cell];
        }
        fewest_joint = std::min(fewest_joint, with_joint);
        most_joint = std::max(most_joint, with_joint);
        fewest = std::min(fewest, slice.size());
        most = std::max(most, slice.size());
        for (std::size_t c = 0; c < cells; ++c) {
          fewest_of_cell[c] = std::min(fewest_of_cell[c], of_cell[c]);
          most_of_cell[c] = std::max(most_of_cell[c], of_cell[c]);
        }
      }
      EXPECT_EQ(seen.size(), cells * trials);
      for (const auto& [trial, count] : seen) EXPECT_EQ(count, 1);
      EXPECT_LE(most_joint - fewest_joint, 1u);  // the slow trials as evenly as they divide
      EXPECT_LE(most - fewest, 2u);              // and so the slices' sizes
      // every cell shared
      for (std::size_t c = 0; c < cells; ++c)
        EXPECT_LE(most_of_cell[c] - fewest_of_cell[c], 2u) << "cell " << c;
    }
}

TEST(MontecarloShards, ASliceBeyondTheCountIsRefused) {
  EXPECT_THROW(shardTrials(3, options(5, 1, 3, 3)), std::invalid_argument);
  EXPECT_THROW(shardTrials(3, options(5, 1, 0, 0)), std::invalid_argument);
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(MontecarloShards, ARecordReadsBackBitForBit) {
  const double kAwkward[] = {0.1,          -0.0,
                             1e-310,       std::numeric_limits<double>::max(),
                             -1.0 / 3.0,   std::numeric_limits<double>::infinity(),
                             6.02214076e23};
  TrialRecord r;
  r.cell = 87;
  r.trial = 999;
  r.result.detected_landmarks = 4;
  r.result.ceiling = {kAwkward[0], std::numeric_limits<double>::quiet_NaN(), kAwkward[2]};
  for (std::size_t e = 0; e < kEstimators; ++e) {
    EstimatorOutcome& o = r.result.estimators[e];
    o.ran = e != 1;
    o.ok = e == 0;
    for (std::size_t rule = 0; rule < kRules; ++rule) {
      o.rules[rule].order = static_cast<int>(e + rule) - 1;
      for (std::size_t s = 0; s < kTestSets; ++s)
        o.rules[rule].mse_ratio[s] = kAwkward[(e + rule + s) % 7];
    }
    if (e == 0)
      o.landmarks = {{kAwkward[3], kAwkward[4]},
                     {std::numeric_limits<double>::quiet_NaN(), kAwkward[1]}};
  }
  const std::string line = formatTrialRecord(r);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  const TrialRecord back = parseTrialRecord(line);
  EXPECT_EQ(back.cell, r.cell);
  EXPECT_EQ(back.trial, r.trial);
  EXPECT_EQ(back.result.detected_landmarks, r.result.detected_landmarks);
  for (std::size_t s = 0; s < kTestSets; ++s)
    EXPECT_TRUE(std::isnan(r.result.ceiling[s])
                    ? std::isnan(back.result.ceiling[s])
                    : sameBits(back.result.ceiling[s], r.result.ceiling[s]));
  for (std::size_t e = 0; e < kEstimators; ++e) {
    SCOPED_TRACE(e);
    const EstimatorOutcome &a = r.result.estimators[e], &b = back.result.estimators[e];
    EXPECT_EQ(a.ran, b.ran);
    EXPECT_EQ(a.ok, b.ok);
    for (std::size_t rule = 0; rule < kRules; ++rule) {
      EXPECT_EQ(a.rules[rule].order, b.rules[rule].order);
      for (std::size_t s = 0; s < kTestSets; ++s)
        EXPECT_TRUE(sameBits(a.rules[rule].mse_ratio[s], b.rules[rule].mse_ratio[s]));
    }
    ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
    for (std::size_t l = 0; l < a.landmarks.size(); ++l) {
      EXPECT_TRUE(std::isnan(a.landmarks[l].radial_m)
                      ? std::isnan(b.landmarks[l].radial_m)
                      : sameBits(a.landmarks[l].radial_m, b.landmarks[l].radial_m));
      EXPECT_TRUE(sameBits(a.landmarks[l].tangential_m, b.landmarks[l].tangential_m));
    }
  }
  EXPECT_EQ(formatTrialRecord(back), line);
}

TEST(MontecarloShards, ADamagedRecordIsRefusedNamingItsColumn) {
  TrialRecord r;
  r.result.estimators[0].landmarks = {{0.5, -0.25}};
  const std::string line = formatTrialRecord(r);
  auto message = [](const std::string& text) {
    try {
      parseTrialRecord(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message(line.substr(0, line.size() / 2)).find("ends early"), std::string::npos);
  EXPECT_NE(message(line + ",0x1p+0").find("beyond the record's end"), std::string::npos);
  EXPECT_NE(message("x" + line).find("column 1 (cell)"), std::string::npos);
  // Column 7 is the closed form's `ran` (after cell, trial, detected landmarks and three ceilings).
  std::size_t at = 0;
  for (int comma = 0; comma < 6; ++comma) at = line.find(',', at) + 1;
  std::string flag = line;
  flag.replace(at, 1, "7");
  EXPECT_NE(message(flag).find("column 7 (ran): expected an integer from 0 to 1, found '7'"),
            std::string::npos)
      << message(flag);
}

TEST(MontecarloShards, TheSlicesPutTogetherGiveTheWholeStudysFiles) {
  TrialConfig config;
  config.path.stops = 8;
  config.path.step_m = 0.3;
  config.path.scans_per_stop = 3;
  StudyGrids g;
  g.sigma_s_m = {0.003, 0.03};
  g.sigma_theta_deg = {1.0, 5.0};
  g.fig9_landmarks = {2};
  const std::vector<Figure> figures = {Figure::fig9, Figure::fig10};
  RunOptions o = options(5, 2, 0, 1);
  o.seed = 11;
  const StudyOutput whole = runStudy(figures, g, config, o);
  const std::vector<Cell> cells = studyCells(figures, g);
  std::vector<std::vector<TrialResult>> merged(cells.size(), std::vector<TrialResult>(o.trials));
  constexpr std::size_t kShards = 3;
  for (std::size_t k = 0; k < kShards; ++k) {
    RunOptions s = o;
    s.shard_index = k;
    s.shard_count = kShards;
    const StudyRun run = runCells(config, cells, s);
    for (const TrialIndex& t : shardTrials(cells.size(), s)) {
      // Through the text a shard writes, as the merge reads it.
      const TrialRecord back =
          parseTrialRecord(formatTrialRecord({t.cell, t.trial, run.results[t.cell][t.trial]}));
      merged[back.cell][back.trial] = back.result;
    }
  }
  const StudyOutput together = studyOutput(figures, g, config, o, merged);
  ASSERT_EQ(whole.files.size(), together.files.size());
  for (std::size_t i = 0; i < whole.files.size(); ++i) {
    SCOPED_TRACE(whole.files[i].first);
    EXPECT_EQ(whole.files[i].first, together.files[i].first);
    EXPECT_EQ(whole.files[i].second, together.files[i].second);
  }
  // A whole study is not run through a shard's options.
  EXPECT_THROW(runStudy(figures, g, config, options(5, 2, 1, 2)), std::invalid_argument);
}

}  // namespace
}  // namespace lidarcal::studies
