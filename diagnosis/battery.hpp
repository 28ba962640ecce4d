// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The battery of discrepancy statistics (step 2 of diagnosis/diagnosis.hpp): what each statistic
// of each mode is, its measured value against its values on the bootstrap replicas, and the
// score statistic aimed at each candidate effect (common/effect.hpp's table).

#include <map>
#include <string>
#include <vector>

#include "diagnosis/diagnosis.hpp"

namespace lidarcal::diagnosis {

/// What a discrepancy statistic is, for the battery table.
struct StatisticInfo {
  const char* name;         ///< e.g. "spread_vs_incidence"
  const char* variable;     ///< what the residuals are compared against
  const char* description;  ///< how it is computed
  bool two_sided;           ///< both directions count
};

/// The statistics of a mode's battery, in output order (one table for both modes: battery.cpp).
const std::vector<StatisticInfo>& statisticInfo(DiagnoseMode mode);

/// The battery's score statistic aimed at an effect in that mode ("" when there is none).
const char* statisticOf(Effect e, DiagnoseMode mode);

/// Fills a Discrepancy from its measured value and its replica values.
Discrepancy makeDiscrepancy(std::string name, std::string variable, std::string description,
                            double value, const std::vector<double>& replicas, bool two_sided);

/// The battery: each listed statistic's measured value against its values on the replicas
/// (statistics missing from `measured` are left out).
std::vector<Discrepancy> makeBattery(const std::vector<StatisticInfo>& infos,
                                     const std::map<std::string, double>& measured,
                                     const std::map<std::string, std::vector<double>>& replicas);

/// The battery's score statistic aimed at the candidate (r.statistic): its p-value and effect size.
void setScore(CandidateResult& r, const std::vector<Discrepancy>& battery);

}  // namespace lidarcal::diagnosis
