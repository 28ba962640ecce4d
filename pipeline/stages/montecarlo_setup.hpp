// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What `lidarcal montecarlo` and `lidarcal montecarlo-merge` share: the study's options and how
// they map into the studies/ structs, the identity of a study (everything its output depends
// on, written into every shard and compared by the merge), and the writing of the output
// directory (text files, then the plots through gnuplot).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "studies/study.hpp"

namespace lidarcal::pipeline {

/// The command's options (defaults as in `lidarcal montecarlo --help`).
struct MonteCarloOptions {
  std::string study = "all";  ///< fig7 ... fig11 or all
  std::string out;            ///< output directory
  std::size_t trials = 0;     ///< trials per cell; 0: the level's default
  /// trials per cell with the joint refinement; 0: the level's default
  std::size_t joint_trials = 0;
  bool no_joint = false;                ///< no joint refinement at all
  int threads = 0;                      ///< worker threads; 0: all cores
  std::uint64_t seed = 1;               ///< study seed
  std::string level = "landmark";       ///< landmark or scan
  std::string angle_noise = "heading";  ///< heading, beams or bearing
  std::string noise_law = "paper";      ///< paper or squared
  double max_distance_m = 4.0;          ///< landmarks' farthest surface from any stop, metres
  double range_max_m = 6.0;             ///< the sensor's reading window, upper end, metres
  int scans_per_stop = 10;              ///< scans averaged at each stop
  int stops = 20;                       ///< stops along the path
  double step_m = 0.15;                 ///< distance between stops, metres
  int max_order = 3;                    ///< highest polynomial order tried
  double noise_scale = -1.0;  ///< multiplies the paper's range noise; < 0: the level's default
  bool quick = false;         ///< coarse grids and fewer trials
  bool overwrite = false;     ///< replace the output directory
  std::string shard;          ///< "K/N": run slice K of N only (empty: the whole study)
};

/// The studies/ structs an option set maps to.
struct StudySetup {
  std::vector<studies::Figure> figures;  ///< the figures of --study
  studies::StudyGrids grids;             ///< full or quick grids
  studies::TrialConfig config;           ///< trial settings
  studies::RunOptions run;  ///< trials, joint trials, seed, threads (no shard, no stop flag)
};

/// Maps the options into the studies/ structs, with the level's defaults filled in. Throws
/// InputError naming the option when one is not valid.
StudySetup studySetup(const MonteCarloOptions& options);

/// Everything the study's output depends on, with the defaults resolved (study, level, noise
/// settings, path, orders, grids, seed, trials, joint trials) and the lidarcal version: two
/// shards with equal identities are slices of one study.
nlohmann::json studyIdentity(const MonteCarloOptions& options, const StudySetup& setup);

/// The options of an identity written by studyIdentity (the merge rebuilds the study from it).
/// Throws InputError naming `file` and the field when one is missing or of the wrong type.
MonteCarloOptions optionsFromIdentity(const nlohmann::json& identity, const std::string& file);

/// Writes the study's files into `dir` (atomically each) and draws its plots with gnuplot there.
/// Returns "" when every plot was drawn, or why they were skipped (gnuplot not installed).
/// Throws std::runtime_error (nothing to commit) when gnuplot fails on a script.
std::string writeStudyOutput(const std::filesystem::path& dir, const studies::StudyOutput& output);

}  // namespace lidarcal::pipeline
