// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene.hpp"

#include "diagnosis/skeleton.hpp"
#include "diagnosis/static_scene/problem.hpp"

namespace lidarcal::diagnosis {

DiagnosisResult diagnoseStatic(const StaticScans& data, const DiagnoseConfig& config,
                               std::vector<WallLine>* walls_out) {
  config.validate();
  DiagnosisResult out;
  out.mode = DiagnoseMode::static_scene;
  out.seed = config.seed;
  out.replicas = config.replicas;
  out.folds = config.folds;
  out.scans = data.scans;
  out.stops = 1;
  out.readings = data.readings.size();
  const std::vector<Effect> candidates = candidateList(config, DiagnoseMode::static_scene);
  static_scene::StaticDiagnosis problem(data, config, candidates, walls_out);
  runDiagnosis(problem, config, candidates, out);
  return out;
}

}  // namespace lidarcal::diagnosis
