// SPDX-License-Identifier: BSD-3-Clause
// The rules that act after the naming in a sequence (diagnosis/sequence/verdict.cpp): an effect
// hidden in readings on a grid or under heavy tails is named beside the symptom, and the
// dark-surface model takes no other effect's place.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "calibration/joint_refinement.hpp"
#include "common/rng.hpp"
#include "diagnose_test_util.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/sequence.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

/// Effects in readings rounded to whole millimetres, as every real sensor reports them. The
/// squared law's noise is 0.5 mm at 0.5 m, so the rounding is real and its model gains held out
/// (+0.01 nats per reading): a hidden effect is named when it holds beside the rounding
/// (SequenceDiagnosis::nameCauseBesideSymptom), clean data are `none` or `quantisation`, never a
/// physical effect. Three cases per effect whose seeds come from a seed this test does not read, 5
/// bootstrap replicas each.
class OnAMillimetreGrid : public ::testing::TestWithParam<const char*> {};

TEST_P(OnAMillimetreGrid, TheEffectIsNamedBesideTheRounding) {
  const std::string e = GetParam();
  int named = 0;
  std::string misses;
  for (const std::uint64_t k : unreadSeeds(nameTag(e + " on a 1 mm grid"), 3)) {
    SCOPED_TRACE(k);
    auto h = test::hiddenEffectCase(e, k);
    h.config.effects.range_resolution_m = 0.001;
    const auto r = diagnoseCase(h, k, 5);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    const bool right = e == "none" ? r.primary_cause == "none" || r.primary_cause == "quantisation"
                                   : r.primary_cause == e;
    named += right;
    if (!right)
      misses += " case " + std::to_string(k) + " (" + h.size + "): " + r.primary_cause + " [" +
                r.decision + "];";
    // The grid is found whatever is named.
    const CandidateResult* q = candidateFor(r, Effect::quantisation);
    ASSERT_NE(q, nullptr);
    ASSERT_TRUE(q->applicable) << q->note;
    EXPECT_EQ(q->estimates.at("grid_m"), 0.001);
  }
  // At least 2 of 3: a method right with probability 0.95 per case fails that with 0.7 %
  // (an angle offset alone is named in 19 of 20, the clean data `none` in 19 of 20 off a grid).
  EXPECT_GE(named, 2) << e << ":" << misses;
}

INSTANTIATE_TEST_SUITE_P(Sequence, OnAMillimetreGrid,
                         ::testing::Values("none", "angle_offset", "incidence_noise",
                                           "landmark_bias"),
                         [](const auto& p) { return std::string(p.param); });

/// Effects where the poles return intensities of 15 to 250 (black to white) and the noise does
/// not depend on them: the dark-surface candidate is fitted (applicable) and must not take the
/// place of the hidden effect, nor be named in clean data. Three cases per effect whose seeds
/// come from a seed this test does not read, 5 bootstrap replicas each.
class WithIntensities : public ::testing::TestWithParam<const char*> {};

TEST_P(WithIntensities, TheDarkSurfaceModelTakesNoOtherEffectsPlace) {
  const std::string e = GetParam();
  int named = 0;
  std::string misses;
  for (const std::uint64_t k : unreadSeeds(nameTag(e + " with intensities"), 3)) {
    SCOPED_TRACE(k);
    auto h = test::hiddenEffectCase(e, k);
    test::giveIntensities(h.config, k);
    const auto r = diagnoseCase(h, k, 5);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    named += r.primary_cause == e;
    if (r.primary_cause != e)
      misses += " case " + std::to_string(k) + " (" + h.size + "): " + r.primary_cause + " [" +
                r.decision + "];";
    const CandidateResult* d = candidateFor(r, Effect::dark_surface);
    ASSERT_NE(d, nullptr);
    ASSERT_TRUE(d->applicable) << d->note;
    EXPECT_FALSE(d->significant) << "dark_surface significant with noise independent of intensity: "
                                 << r.decision;
  }
  EXPECT_GE(named, 2) << e << ":" << misses;
}

INSTANTIATE_TEST_SUITE_P(Sequence, WithIntensities,
                         ::testing::Values("none", "incidence_noise", "landmark_bias"),
                         [](const auto& p) { return std::string(p.param); });

TEST(DiagnoseSequence, WithoutIntensitiesTheDarkSurfaceModelIsNotApplicable) {
  // The paper field as the seeds simulate it: no intensity recorded. The candidate is listed, not
  // fitted, and says what to record.
  const auto h = test::hiddenEffectCase("none", 5);
  const auto r = diagnoseCase(h, 5, 5);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  const CandidateResult* d = candidateFor(r, Effect::dark_surface);
  ASSERT_NE(d, nullptr);
  EXPECT_FALSE(d->applicable);
  EXPECT_NE(d->note.find("intensit"), std::string::npos) << d->note;
  EXPECT_FALSE(d->significant);
}

TEST(DiagnoseSequence, AnAngleOffsetUnderHeavyTailsIsNamedByItsLikelihoodRatioBesideTheT) {
  // A lidar yawed 2-3 degrees in Student-t noise of 3 degrees of freedom: the t comes first, and
  // the offset's evidence is in sample (its held-out gain beside the t is about 2 standard errors),
  // so it is named by the likelihood ratio of the two t fits
  // (SequenceDiagnosis::nameCauseBesideSymptom; named in 18 of 20 fresh cases,
  // docs/results/hidden-effects.md). Three cases whose seeds come from a seed this test does not
  // read, at least 2 named.
  int named = 0;
  std::string misses;
  for (const std::uint64_t k : unreadSeeds(nameTag("angle offset under tails"), 3)) {
    SCOPED_TRACE(k);
    auto h = test::hiddenEffectCase("angle_offset", k);
    h.config.effects.noise_student_dof = 3.0;
    const auto r = diagnoseCase(h, k, 5);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    named += r.primary_cause == "angle_offset";
    if (r.primary_cause != "angle_offset")
      misses += " case " + std::to_string(k) + ": " + r.primary_cause + " [" + r.decision + "];";
    const CandidateResult* a = candidateFor(r, Effect::angle_offset);
    ASSERT_NE(a, nullptr);
    if (r.primary_cause == "angle_offset" && a->estimates.count("heldout_gain_beside_tails")) {
      EXPECT_TRUE(a->estimates.count("p_likelihood_ratio_beside_tails")) << r.decision;
    }
  }
  EXPECT_GE(named, 2) << misses;
}

TEST(DiagnoseSequence, APhysicalEffectUnderHeavyTailsIsNamedAndTheTailsStayBesideIt) {
  // Per-pole range offsets (RMS 2-2.5 cm) in Student-t noise of 3 degrees of freedom: the named
  // cause must be physical. Either the offsets gain most, or the t comes first and the offsets hold
  // beside it (refitted with the t, held out: SequenceDiagnosis::refineCause; in 3 of 5 development
  // cases). Three cases whose seeds come from a seed this test does not read.
  int beside = 0;
  for (const std::uint64_t k : unreadSeeds(nameTag("offsets under tails"), 3)) {
    SCOPED_TRACE(k);
    auto h = test::hiddenEffectCase("landmark_bias", k);
    h.config.effects.noise_student_dof = 3.0;
    const auto r = diagnoseCase(h, k, 5);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    EXPECT_EQ(r.primary_cause, "landmark_bias") << r.decision;
    for (const auto& c : r.candidates) {
      if (c.effect == Effect::heavy_tails) {
        EXPECT_TRUE(c.significant);
        EXPECT_LT(c.estimates.at("student_dof"), 6.0);
      }
      // Checked beside the t: the gain over the t alone is reported with its standard error.
      if (c.effect == Effect::landmark_bias && c.estimates.count("heldout_gain_beside_tails")) {
        ++beside;
        EXPECT_GT(c.estimates.at("heldout_gain_beside_tails"),
                  3.0 * c.estimates.at("heldout_gain_beside_tails_se"));
      }
    }
    std::printf("case %llu: %s (%s)\n", static_cast<unsigned long long>(k), r.primary_cause.c_str(),
                r.decision.c_str());
  }
  std::printf("checked beside the tails in %d of 3\n", beside);
}

}  // namespace
}  // namespace lidarcal::diagnosis
