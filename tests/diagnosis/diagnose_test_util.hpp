// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Helpers of the diagnosis' hidden-effect tests: case seeds drawn from a seed the tests do not
// read, the case and replica counts the environment can raise (LIDARCAL_DIAGNOSE_CASES,
// LIDARCAL_DIAGNOSE_REPLICAS, LIDARCAL_DIAGNOSE_FIRST; tests/CMakeLists.txt registers the long
// runs), and a hidden sequence case diagnosed.

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "common/rng.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/sequence.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::diagnosis {

/// Hidden-effect cases of `effect` (LIDARCAL_DIAGNOSE_CASES for every effect). By default 10 for
/// the clean data and angle_offset, the two whose fresh rate is below 20 of 20
/// (docs/results/hidden-effects.md), and 5 for the others: a case costs about 4 s of CPU (candidate
/// fits and cross-validation, not the replicas), and 10 for every effect would make the default
/// suite about 60 % longer, against a budget of 30 %. A deliberate bug that breaks an effect's
/// likelihood ratio or its sign fails its check in every case, so 5 cases catch it as surely as 10.
inline int casesPerEffect(const std::string& effect) {
  const char* env = std::getenv("LIDARCAL_DIAGNOSE_CASES");
  if (env && *env) return std::max(1, std::atoi(env));
  return effect == "none" || effect == "angle_offset" ? 10 : 5;
}

/// Bootstrap replicas of the hidden-effect runs (LIDARCAL_DIAGNOSE_REPLICAS). The default run
/// takes the fewest the method allows (5) to keep the suite's time; the long run and
/// docs/results/hidden-effects.md take the command's default (19).
inline int replicasPerCase() {
  const char* env = std::getenv("LIDARCAL_DIAGNOSE_REPLICAS");
  return env && *env ? std::max(5, std::atoi(env)) : 5;
}

/// A stream tag from a case's name (FNV-1a: the same on every platform).
inline std::uint64_t nameTag(const std::string& name) {
  std::uint64_t h = 14695981039346656037ULL;
  for (unsigned char ch : name) h = (h ^ ch) * 1099511628211ULL;
  return h;
}

/// Seeds for the hidden effects, drawn from a seed the tests do not read (data generated with seeds
/// the tests do not choose), one stream per `tag`, disjoint in practice from the development seeds
/// (all below 1000).
inline std::vector<std::uint64_t> unreadSeeds(std::uint64_t tag, int n) {
  auto rng = makeRng(20261125, tag);
  std::uniform_int_distribution<std::uint64_t> seed_of(1000, 1000000);
  std::vector<std::uint64_t> out(static_cast<std::size_t>(n));
  for (auto& s : out) s = seed_of(rng);
  return out;
}

/// Case seeds of the hidden-effect runs of `effect`: n consecutive from LIDARCAL_DIAGNOSE_FIRST
/// when it is set (the long run and docs/results/hidden-effects.md: 21-40), else drawn by
/// unreadSeeds.
inline std::vector<std::uint64_t> caseSeeds(const std::string& effect, int n) {
  const char* env = std::getenv("LIDARCAL_DIAGNOSE_FIRST");
  if (env && *env) {
    std::vector<std::uint64_t> out;
    for (int k = 0; k < n; ++k)
      out.push_back(static_cast<std::uint64_t>(std::max(1, std::atoi(env)) + k));
    return out;
  }
  return unreadSeeds(nameTag(effect), n);
}

/// Hidden case h simulated and diagnosed with diagnose seed `seed` and `replicas` bootstrap
/// replicas; one replica for the extended simulation, whose closeness these tests do not look at.
inline DiagnosisResult diagnoseCase(const test::HiddenEffectCase& h, std::uint64_t seed,
                                    int replicas) {
  const auto s = simulation::simulateLandmarkLevel(h.config, h.seed);
  DiagnoseConfig dc;
  dc.seed = seed;
  dc.replicas = replicas;
  dc.closeness_replicas = 1;
  return diagnoseSequence(s.obs, dc);
}

/// The candidate row of effect `e` in `r` (nullptr when `e` was not a candidate).
inline const CandidateResult* candidateFor(const DiagnosisResult& r, Effect e) {
  const auto c = std::find_if(r.candidates.begin(), r.candidates.end(),
                              [e](const CandidateResult& x) { return x.effect == e; });
  return c == r.candidates.end() ? nullptr : &*c;
}

/// The hidden size of a signed effect (0: not signed) and the key of its estimate.
inline std::pair<double, const char*> signedTruth(const std::string& e,
                                                  const test::HiddenEffectCase& h) {
  if (e == "incidence_bias") return {h.config.effects.incidence_bias_m, "incidence_bias_m"};
  if (e == "range_drift")
    return {h.config.effects.range_drift_m_per_scan, "range_drift_m_per_scan"};
  if (e == "angle_offset") return {h.config.mount_yaw_rad, "angle_offset_deg"};
  return {0.0, ""};
}

}  // namespace lidarcal::diagnosis
