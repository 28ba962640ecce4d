// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One trial's result as a line of text that reads back bit for bit: what a shard of a study
// (runner.hpp, shardTrials) hands to the merge. Every number of a TrialResult is kept, doubles in
// C99 hexadecimal floating point (printf "%a"), so the merged study summarises exactly the values
// a single process would have. Text only: the pipeline writes and reads the files.
//
// A record is comma-separated:
//   cell, trial, detected_landmarks, ceiling[3],
//   then per estimator (closed_form, joint, oracle):
//     ran, ok, per rule (aic, aic_parsimonious): order, mse_ratio[3];
//     landmarks n, then n pairs radial_m, tangential_m

#include <cstddef>
#include <string>

#include "studies/trial.hpp"

namespace lidarcal::studies {

/// A trial's place in the study and its result.
struct TrialRecord {
  std::size_t cell = 0;   ///< index of the cell in the study's cells (studyCells)
  std::size_t trial = 0;  ///< trial number in the cell, 0-based
  TrialResult result;     ///< what the trial gave
};

/// The comment line that opens a file of records: what the columns are.
std::string trialRecordHeader();

/// The record of one trial, without a line break.
std::string formatTrialRecord(const TrialRecord& record);

/// Reads a record written by formatTrialRecord. Throws std::invalid_argument naming the column
/// (e.g. "column 7 (joint ok): expected 0 or 1") when the line is not one.
TrialRecord parseTrialRecord(const std::string& line);

}  // namespace lidarcal::studies
