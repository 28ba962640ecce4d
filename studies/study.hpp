// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A whole Monte Carlo study: the cells of the requested figures (each cell run once even when
// several figures use it), their trials, and the text of every output file.

#include <string>
#include <utility>
#include <vector>

#include "studies/figures.hpp"
#include "studies/runner.hpp"

namespace lidarcal::studies {

/// Distinct cells of the figures, in order of first appearance.
std::vector<Cell> studyCells(const std::vector<Figure>& figures, const StudyGrids& grids);

struct StudyOutput {
  /// (file name, content): per figure <fig>.csv, <fig>.gp (writes <fig>.png), <fig>.md, and
  /// summary.md with every figure's summary. Empty when interrupted.
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<std::string> gnuplot_scripts;  ///< the .gp files to run, in order
  bool interrupted = false;                  ///< stopped before every trial ran
  std::size_t cells = 0;                     ///< distinct cells run
};

/// The output files of a study from every trial's result (results[cell][trial], cells in the order
/// of studyCells): what runStudy writes, whether the trials ran in this process or were read back
/// from shards. Depends on (figures, grids, config, options.seed, options.trials,
/// options.joint_trials, results) only.
StudyOutput studyOutput(const std::vector<Figure>& figures, const StudyGrids& grids,
                        const TrialConfig& config, const RunOptions& options,
                        const std::vector<std::vector<TrialResult>>& results);

/// Runs the study (every trial: options.shard_count must be 1). The output depends on (figures,
/// grids, config, options.seed, options.trials, options.joint_trials) only, not on options.threads.
StudyOutput runStudy(const std::vector<Figure>& figures, const StudyGrids& grids,
                     const TrialConfig& config, const RunOptions& options);

}  // namespace lidarcal::studies
