// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/skeleton.hpp"

namespace lidarcal::diagnosis {

void runDiagnosis(DiagnosisMode& mode, const DiagnoseConfig& config,
                  const std::vector<Effect>& candidates, DiagnosisResult& out) {
  // 1. Baseline: the published model.
  reportProgress(config, "baseline fit", 0, 0);
  if (!mode.fitBaseline(out)) return;
  const std::map<std::string, double> measured = mode.measuredStatistics(out);
  // 2. Parametric bootstrap from the fitted baseline: the battery's p-values.
  std::map<std::string, std::vector<double>> replica_stats;
  const auto replicas = static_cast<std::size_t>(config.replicas);
  for (int b = 0; b < config.replicas; ++b) {
    reportProgress(config, "bootstrap replicas", static_cast<std::size_t>(b), replicas);
    mode.replica(b, replica_stats, out);
  }
  reportProgress(config, "bootstrap replicas", replicas, replicas);
  out.battery = makeBattery(mode.statisticInfo(), measured, replica_stats);
  // 3. Candidates: held-out gain, delta AIC, identifiability.
  HeldOut held(candidates.size());
  reportProgress(config, kHeldOutStage, 0, 0);
  mode.heldOut(held);
  if (held.base.empty()) {
    out.status.code = StatusCode::cross_validation_failed;
    out.status.message = mode.noHeldOut();
    return;
  }
  out.baseline_heldout_nats_per_point = held.baselineMean();
  mode.beforeCandidates(out);
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    reportProgress(config, "candidate tests", c, candidates.size());
    out.candidates.push_back(mode.candidate(c, held, out));
  }
  reportProgress(config, "candidate tests", candidates.size(), candidates.size());
  mode.afterCandidates(out);
  // 4. The cause: the rules of diagnosis/rules.hpp, in the table's order.
  out.primary_cause = nameCause(out.candidates, config.alpha, out.decision, mode.nestedEffects());
  mode.refineCause(out);
  // 5. The extended model and how close its simulation comes to the data.
  reportProgress(config, "extended model", 0, 0);
  out.closeness_baseline = mode.closenessBaseline(out);
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    if (toString(candidates[c]) != out.primary_cause) continue;
    const CandidateResult& r = out.candidates[c];
    out.extended_parameters = r.estimates;
    out.gain_heldout_nats_per_point = r.heldout_gain_nats_per_point;
    out.gain_delta_aic = r.delta_aic;
    mode.extend(c, out);
    break;
  }
}

}  // namespace lidarcal::diagnosis
