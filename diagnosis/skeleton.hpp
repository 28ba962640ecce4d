// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The five steps of a diagnosis (diagnosis/diagnosis.hpp), shared by both kinds of data: the
// driver that runs them on a mode's problem object (diagnosis/sequence/problem.hpp,
// diagnosis/static_scene/problem.hpp). Internal to the diagnosis library.

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "diagnosis/battery.hpp"
#include "diagnosis/diagnosis.hpp"
#include "diagnosis/held_out.hpp"
#include "diagnosis/rules.hpp"

namespace lidarcal::diagnosis {

/// The stage in which a mode fits its candidates on the folds (modes report their own counts).
inline constexpr const char* kHeldOutStage = "held-out fits";

/// Tells config.progress (when set) that `stage` is at `done` of `total`.
inline void reportProgress(const DiagnoseConfig& config, const char* stage, std::size_t done,
                           std::size_t total) {
  if (config.progress) config.progress(stage, done, total);
}

/// What a kind of data must provide for the five steps of diagnosis.hpp, in the order
/// runDiagnosis calls them. What a mode draws at random is seeded per replica.
class DiagnosisMode {
 public:
  virtual ~DiagnosisMode() = default;

  // 1. The published model. False: out.status says why it could not be fitted.
  virtual bool fitBaseline(DiagnosisResult& out) = 0;
  /// The battery's statistics on the data (also recorded in out.measured).
  virtual std::map<std::string, double> measuredStatistics(DiagnosisResult& out) = 0;

  // 2. Parametric bootstrap: replica `b` simulated from the baseline, its statistics appended.
  virtual void replica(int b, std::map<std::string, std::vector<double>>& stats,
                       DiagnosisResult& out) = 0;
  virtual const std::vector<StatisticInfo>& statisticInfo() const = 0;

  // 3. Candidates scored out of sample. heldOut fills the baseline's and each candidate's
  // held-out terms; an empty baseline stops the diagnosis with noHeldOut() as the reason.
  virtual void heldOut(HeldOut& held) = 0;
  virtual const char* noHeldOut() const = 0;
  virtual void beforeCandidates(DiagnosisResult& out) = 0;
  virtual CandidateResult candidate(std::size_t c, const HeldOut& held,
                                    const DiagnosisResult& out) = 0;
  virtual void afterCandidates(DiagnosisResult& out) = 0;

  // 4. The cause: pairs (outer, inner) where the inner effect is nested in the outer (see
  // nameCause), then the mode's own rules of diagnosis/rules.hpp after nameCause.
  virtual std::vector<std::pair<Effect, Effect>> nestedEffects() const = 0;
  virtual void refineCause(DiagnosisResult& out) = 0;

  // 5. How close the baseline's simulation comes to the data, and the model extended by
  // candidate `c` (the named cause).
  virtual Closeness closenessBaseline(const DiagnosisResult& out) const = 0;
  virtual void extend(std::size_t c, DiagnosisResult& out) const = 0;
};

/// Runs the five steps of diagnosis.hpp on `mode`: the baseline, the bootstrap battery, the
/// candidates held out, the cause and the extended model, into `out`.
void runDiagnosis(DiagnosisMode& mode, const DiagnoseConfig& config,
                  const std::vector<Effect>& candidates, DiagnosisResult& out);

}  // namespace lidarcal::diagnosis
