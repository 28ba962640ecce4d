// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shards of a Monte Carlo study on disk (docs/FORMAT.md, "Monte Carlo shards"): what
// `lidarcal montecarlo --shard K/N` writes, and how `lidarcal montecarlo-merge` reads the N
// directories back, checks that they are the N slices of one study, each exactly once, and
// puts every trial's result back in its place, bit for bit.
//
//   DIR/shard.json   {"format": "lidarcal-montecarlo-shard/1", "shard": K, "shards": N,
//                     "trials_in_shard": M, "study": {the study's identity}}
//   DIR/trials.csv   a comment line, then one record per trial of the slice
//   (studies/trial_record.hpp)

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/stages/montecarlo_setup.hpp"
#include "studies/runner.hpp"

namespace lidarcal::pipeline {

/// Reads "K/N" (1 <= K <= N) into run.shard_index = K - 1 and run.shard_count = N. Throws
/// InputError naming --shard.
void parseShard(const std::string& text, studies::RunOptions& run);

/// Writes shard.json and trials.csv of slice run.shard_index into `dir` (atomically each): the
/// results of the trials `slice` lists (shardTrials), in that order.
void writeShard(const std::filesystem::path& dir, const nlohmann::json& identity,
                const studies::RunOptions& run, const std::vector<studies::TrialIndex>& slice,
                const studies::StudyRun& results);

/// A study put back together from its shards.
struct MergedStudy {
  MonteCarloOptions options;  ///< the study's options, from the shards' identity
  std::vector<std::vector<studies::TrialResult>> results;  ///< results[cell][trial], every trial
};

/// Reads the shard directories of one study. Throws InputError (exit 2) naming the file and the
/// field when a directory is not a shard, when two shards differ in their study (another
/// --study, --seed, trial count or option, or another lidarcal), when a slice is given twice or
/// one is missing, or when a slice's trials.csv does not hold exactly its trials.
MergedStudy readShards(const std::vector<std::filesystem::path>& dirs);

}  // namespace lidarcal::pipeline
