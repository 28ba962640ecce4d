// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The verdict: how the candidates' fits become a named cause (step 4 of diagnosis/diagnosis.hpp),
// as one ordered table of rules. Each rule has an id, the data it applies to, the stage where it
// acts, its condition, its threshold and one line of why; the code that applies a rule cites its
// id, and docs/DIAGNOSIS.md prints the same table in the same order. The evidence behind the
// thresholds is in docs/results/hidden-effects.md (sequences) and docs/results/static-diagnosis.md
// (one pose).

#include <string>
#include <utility>
#include <vector>

#include "diagnosis/diagnosis.hpp"

namespace lidarcal::diagnosis {

namespace rules {
/// Two held-out gains count as equal within this many standard errors of their difference.
inline constexpr double kCloseGainSe = 2.0;
/// An effect is identifiable when its estimate stands this many standard errors clear of zero
/// (or its standard error is below the smallest size worth naming).
inline constexpr double kIdentifiableEstimateSe = 4.0;
/// Refits of one model from one start differ by up to this much in nats (a geometry term's fit
/// below the baseline's by more than twice this is not at its optimum).
inline constexpr double kNestedSlackNats = 0.5;
/// A reading grid is fine, and the in-sample likelihood ratio beside it counts, up to this many
/// times the noise of the readings' 10th percentile (Sheppard's correction holds).
inline constexpr double kFineGridOverNoise = 2.0;
/// Darkness and ln range this correlated over the beams cannot be told apart (static data).
inline constexpr double kConfounded = 0.95;
/// A pooled contamination above this share of the readings is the main component, not a tail.
inline constexpr double kMostReadings = 0.5;
}  // namespace rules

/// One rule of the verdict (docs/DIAGNOSIS.md, "The rules").
struct VerdictRule {
  const char* id;  ///< the name the code cites where it applies the rule
  /// "both", "sequence", "drive" (a sequence under the motion prior) or "static"
  const char* data;
  /// "candidate" (its p-value, step 3), "name" (nameCause) or "refine" (after it)
  const char* stage;
  const char* condition;  ///< what it checks and what it does, in words
  /// its number (the constant of rules:: or calibration/ it uses), or "alpha" (--alpha, 0.01)
  const char* threshold;
  const char* reason;  ///< one line of why
};

/// Every rule, in the order the diagnosis applies them.
const std::vector<VerdictRule>& verdictRules();

/// Rules `significant` to `indistinguishable`: names the cause from the candidates (fills
/// `significant` and the Holm p-values first). `nested`: pairs (simpler, richer), e.g. one
/// zero-angle offset is the mean of per-stop headings; `indistinguishable`: pairs the data cannot
/// tell apart when their gains are close. Returns the cause (an effect's name, none or
/// not_identifiable); `decision` receives the reason in words.
std::string nameCause(std::vector<CandidateResult>& candidates, double alpha, std::string& decision,
                      const std::vector<std::pair<Effect, Effect>>& nested = {},
                      const std::vector<std::pair<Effect, Effect>>& indistinguishable = {});

}  // namespace lidarcal::diagnosis
