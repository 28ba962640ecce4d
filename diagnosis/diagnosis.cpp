// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/diagnosis.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace lidarcal::diagnosis {

const char* toString(DiagnoseMode mode) {
  return mode == DiagnoseMode::sequence ? "sequence" : "static";
}

void DiagnoseConfig::validate() const {
  if (replicas < 5) throw std::invalid_argument("DiagnoseConfig: replicas must be >= 5");
  if (folds < 2) throw std::invalid_argument("DiagnoseConfig: folds must be >= 2");
  if (!(alpha > 0.0 && alpha < 1.0))
    throw std::invalid_argument("DiagnoseConfig: alpha must be in (0, 1)");
  if (max_order < 1 || max_order > 6)
    throw std::invalid_argument("DiagnoseConfig: max_order must be 1..6");
  if (!(outlier_floor >= 0.0 && outlier_floor < 0.5))
    throw std::invalid_argument("DiagnoseConfig: outlier_floor must be in [0, 0.5)");
  if (!(sigma_s_m > 0.0)) throw std::invalid_argument("DiagnoseConfig: sigma_s_m must be positive");
  if (closeness_replicas < 1)
    throw std::invalid_argument("DiagnoseConfig: closeness_replicas must be >= 1");
}

std::vector<Effect> candidateList(const DiagnoseConfig& config, DiagnoseMode mode) {
  std::vector<Effect> all;
  for (const auto& i : effectTable())
    if ((mode == DiagnoseMode::sequence ? i.sequence_statistic : i.static_statistic) != nullptr)
      all.push_back(i.effect);
  if (config.candidates.empty()) return all;
  for (Effect e : config.candidates)
    if (std::find(all.begin(), all.end(), e) == all.end())
      throw std::invalid_argument(
          std::string("diagnose: '") + toString(e) + "' is not a candidate effect for " +
          (mode == DiagnoseMode::sequence ? "a sequence" : "a static recording"));
  return config.candidates;
}

}  // namespace lidarcal::diagnosis
