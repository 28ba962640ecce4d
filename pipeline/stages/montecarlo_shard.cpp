// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/montecarlo_shard.hpp"

#include <cstdlib>
#include <map>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_util.hpp"
#include "io/line_reader.hpp"
#include "studies/trial_record.hpp"

namespace lidarcal::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr const char* kShardFormat = "lidarcal-montecarlo-shard/1";
constexpr const char* kSameStudy =
    "merge the shards of one study: the same --study, --seed, --trials and options, and the same "
    "lidarcal";

/// What shard.json says about one directory.
struct ShardHeader {
  fs::path dir;             ///< the shard directory
  std::string file;         ///< its shard.json, for messages
  std::size_t index = 0;    ///< 0-based slice
  std::size_t count = 0;    ///< slices of the study
  std::size_t trials = 0;   ///< records trials.csv must hold
  nlohmann::json identity;  ///< the study's identity
};

std::string slice(std::size_t index, std::size_t count) {
  return std::to_string(index + 1) + "/" + std::to_string(count);
}

ShardHeader readHeader(const fs::path& dir) {
  ShardHeader h;
  h.dir = dir;
  h.file = (dir / "shard.json").string();
  if (!fs::is_regular_file(dir / "shard.json"))
    throw InputError(dir.string(), "shard.json", "not found: this is not a shard directory",
                     "pass the directories `lidarcal montecarlo --shard K/N` wrote");
  const nlohmann::json j = io::readJsonFile(dir / "shard.json");
  const io::JsonView v(h.file, j);
  v.requireObject();
  if (v.getString("format") != kShardFormat)
    v.fail("format", "is '" + v.getString("format") + "', expected '" + kShardFormat + "'");
  h.count = static_cast<std::size_t>(v.getPositiveInt("shards"));
  const int k = v.getPositiveInt("shard");
  if (static_cast<std::size_t>(k) > h.count)
    v.fail("shard",
           "is " + std::to_string(k) + ", beyond the " + std::to_string(h.count) + " shards");
  h.index = static_cast<std::size_t>(k - 1);
  const int m = v.getInt("trials_in_shard");
  if (m < 0) v.fail("trials_in_shard", "must not be negative");
  h.trials = static_cast<std::size_t>(m);
  h.identity = v.child("study").json();
  if (!h.identity.is_object()) v.fail("study", "must be an object");
  return h;
}

/// The first field in which two identities differ ("" when equal): the options a user sets most
/// often first, then the others (a study of another figure also has another cell count; the
/// message names the figure).
std::string firstDifference(const nlohmann::json& a, const nlohmann::json& b) {
  for (const char* key :
       {"lidarcal_version", "study", "seed", "trials", "joint_trials", "quick", "level"})
    if (a.contains(key) != b.contains(key) || (a.contains(key) && a.at(key) != b.at(key)))
      return key;
  for (const auto& [key, value] : a.items())
    if (!b.contains(key) || b.at(key) != value) return key;
  for (const auto& [key, value] : b.items())
    if (!a.contains(key)) return key;
  return "";
}

std::string shown(const nlohmann::json& j, const std::string& key) {
  return j.contains(key) ? j.at(key).dump() : "(absent)";
}

/// Every shard of the study exactly once, all of one study; returns them ordered by slice.
std::vector<ShardHeader> checkSlices(std::vector<ShardHeader> shards) {
  const ShardHeader& first = shards.front();
  for (const ShardHeader& h : shards) {
    if (const std::string key = firstDifference(h.identity, first.identity); !key.empty())
      throw InputError(h.file, "study." + key,
                       "is " + shown(h.identity, key) + ", but " + first.file + " has " +
                           shown(first.identity, key),
                       kSameStudy);
    if (h.count != first.count)
      throw InputError(h.file, "shards",
                       "is " + std::to_string(h.count) + ", but " + first.file + " has " +
                           std::to_string(first.count),
                       "merge the shards of one run, all cut with the same --shard K/N count");
  }
  std::vector<const ShardHeader*> by_slice(first.count, nullptr);
  for (const ShardHeader& h : shards) {
    if (by_slice[h.index])
      throw InputError(h.file, "shard",
                       "slice " + slice(h.index, h.count) + " is given twice (also " +
                           by_slice[h.index]->file + ")",
                       "pass each shard directory once");
    by_slice[h.index] = &h;
  }
  std::string missing;
  for (std::size_t k = 0; k < first.count; ++k)
    if (!by_slice[k]) missing += (missing.empty() ? "" : ", ") + slice(k, first.count);
  if (!missing.empty())
    throw InputError(
        "", "shards", "missing slice(s) " + missing + " of the study in " + first.file,
        "run `lidarcal montecarlo --shard K/N` for each and pass every shard directory");
  std::vector<ShardHeader> ordered;
  for (const ShardHeader* h : by_slice) ordered.push_back(*h);
  return ordered;
}

/// Reads one shard's trials.csv into `results`; it must hold exactly the trials of its slice.
void readRecords(const ShardHeader& h, const std::vector<studies::TrialIndex>& expected,
                 std::vector<std::vector<studies::TrialResult>>& results) {
  const fs::path file = h.dir / "trials.csv";
  if (!fs::is_regular_file(file))
    throw InputError(h.dir.string(), "trials.csv", "not found",
                     "run the shard again: its directory is incomplete");
  if (expected.size() != h.trials)
    throw InputError(h.file, "trials_in_shard",
                     "is " + std::to_string(h.trials) + ", but slice " + slice(h.index, h.count) +
                         " of this study has " + std::to_string(expected.size()) + " trials",
                     "run the shard again");
  std::map<std::pair<std::size_t, std::size_t>, bool> pending;  // trial -> read yet
  for (const auto& t : expected) pending[{t.cell, t.trial}] = false;
  io::LineReader in(file);
  std::string line;
  std::size_t read = 0;
  while (in.next(line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::string where = "line " + std::to_string(in.lineNumber());
    studies::TrialRecord r;
    try {
      r = studies::parseTrialRecord(line);
    } catch (const std::invalid_argument& e) {
      throw InputError(file.string(), where, e.what(), "run the shard again: the file is damaged");
    }
    const auto it = pending.find({r.cell, r.trial});
    if (it == pending.end() || it->second)
      throw InputError(file.string(), where,
                       "trial " + std::to_string(r.trial) + " of cell " + std::to_string(r.cell) +
                           (it == pending.end() ? " is not in slice " + slice(h.index, h.count)
                                                : " appears twice"),
                       "run the shard again");
    it->second = true;
    results[r.cell][r.trial] = std::move(r.result);
    ++read;
  }
  if (read != expected.size())
    throw InputError(file.string(), "records",
                     "holds " + std::to_string(read) + " of the " +
                         std::to_string(expected.size()) + " trials of slice " +
                         slice(h.index, h.count),
                     "run the shard again: the file is incomplete");
}

}  // namespace

void parseShard(const std::string& text, studies::RunOptions& run) {
  const std::size_t slash = text.find('/');
  char* end_k = nullptr;
  char* end_n = nullptr;
  const std::string k_text = slash == std::string::npos ? text : text.substr(0, slash);
  const std::string n_text = slash == std::string::npos ? "" : text.substr(slash + 1);
  const unsigned long long k = std::strtoull(k_text.c_str(), &end_k, 10);
  const unsigned long long n = std::strtoull(n_text.c_str(), &end_n, 10);
  const bool digits = !k_text.empty() && !n_text.empty() &&
                      k_text.find_first_not_of("0123456789") == std::string::npos &&
                      n_text.find_first_not_of("0123456789") == std::string::npos;
  if (!digits || *end_k != '\0' || *end_n != '\0' || k < 1 || n < 1 || k > n || n > 1000000)
    throw InputError("", "--shard", "'" + text + "' is not K/N with 1 <= K <= N",
                     "e.g. --shard 3/8 for the third of eight slices (a Slurm array task: "
                     "$((SLURM_ARRAY_TASK_ID + 1))/N)");
  run.shard_index = static_cast<std::size_t>(k - 1);
  run.shard_count = static_cast<std::size_t>(n);
}

void writeShard(const fs::path& dir, const nlohmann::json& identity, const studies::RunOptions& run,
                const std::vector<studies::TrialIndex>& trials, const studies::StudyRun& results) {
  std::string text = studies::trialRecordHeader() + "\n";
  for (const auto& t : trials)
    text += studies::formatTrialRecord({t.cell, t.trial, results.results[t.cell][t.trial]}) + "\n";
  io::writeTextAtomically(dir / "trials.csv", text);
  nlohmann::json j;
  j["format"] = kShardFormat;
  j["shard"] = run.shard_index + 1;
  j["shards"] = run.shard_count;
  j["trials_in_shard"] = trials.size();
  j["study"] = identity;
  io::writeTextAtomically(dir / "shard.json", j.dump(2) + "\n");
}

MergedStudy readShards(const std::vector<fs::path>& dirs) {
  if (dirs.empty())
    throw InputError("", "SHARD_DIR", "no shard directory given",
                     "pass every shard directory of the study");
  std::vector<ShardHeader> shards;
  for (const fs::path& d : dirs) shards.push_back(readHeader(d));
  shards = checkSlices(std::move(shards));
  MergedStudy merged;
  merged.options = optionsFromIdentity(shards.front().identity, shards.front().file);
  const StudySetup setup = studySetup(merged.options);
  const std::size_t cells = studies::studyCells(setup.figures, setup.grids).size();
  const nlohmann::json& identity = shards.front().identity;
  if (!identity.contains("cells") || !identity.at("cells").is_number_unsigned() ||
      identity.at("cells").get<std::size_t>() != cells)
    throw InputError(shards.front().file, "study.cells",
                     "is " + shown(shards.front().identity, "cells") + ", but the study has " +
                         std::to_string(cells) + " cells",
                     kSameStudy);
  merged.results.assign(cells, std::vector<studies::TrialResult>(setup.run.trials));
  for (const ShardHeader& h : shards) {
    studies::RunOptions run = setup.run;
    run.shard_index = h.index;
    run.shard_count = h.count;
    readRecords(h, studies::shardTrials(cells, run), merged.results);
  }
  return merged;
}

}  // namespace lidarcal::pipeline
