// SPDX-License-Identifier: BSD-3-Clause
// The tails of a static recording explained (diagnosis/static_scene/tail_attribution.cpp and
// verdict.cpp): extra-wide errors in one class of beams are named by their physical cause, and
// the tail study is deterministic.

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
#include "diagnosis/static_scene.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

/// Where the test puts the extra-wide errors, and what the diagnosis must say about them.
struct TailTruth {
  const char* name;
  test::TailWhere where;
  const char* effect;  ///< the physical cause to name
  const char* cls;     ///< the class of beams holding most of the tail readings
};

class StaticTails : public ::testing::TestWithParam<TailTruth> {};

/// Extra-wide errors (10 % of the readings of one class of beams, 5 cm) only at grazing incidence,
/// only at depth edges or only on a dark wall: named by the physical effect (not heavy_tails), the
/// tails put in that class. Four seeds the method was not tuned on; at least 3 right (a method
/// right 95 % of the time passes with probability 0.99).
TEST_P(StaticTails, DiagnoseNamesThePhysicalCauseAndTheBeamsThatCarryTheTails) {
  const TailTruth& c = GetParam();
  int right = 0;
  std::string log;
  for (const std::uint64_t seed : unreadSeeds(nameTag(c.effect) + 301, 4)) {
    DiagnoseConfig dc;
    dc.replicas = 5;
    dc.seed = seed;
    const auto r = diagnoseStatic(test::staticRoomWithTails(c.where, 0.10, 0.05, seed), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    ASSERT_TRUE(r.tails.fitted) << r.tails.note;
    const std::string top = test::dominantTailClass(r.tails);
    right += r.primary_cause == c.effect && r.tails.cause == c.effect && top == c.cls;
    log += " seed " + std::to_string(seed) + ": " + r.primary_cause + ", tails " + r.tails.cause +
           ", class " + top + ";";
  }
  std::printf("%s:%s\n", c.name, log.c_str());
  EXPECT_GE(right, 3) << log;
}

INSTANTIATE_TEST_SUITE_P(
    Room, StaticTails,
    ::testing::Values(TailTruth{"grazing", test::TailWhere::grazing, "incidence_noise", "grazing"},
                      TailTruth{"edge", test::TailWhere::edge, "mixed_pixels", "edge"},
                      TailTruth{"dark", test::TailWhere::dark, "dark_surface", "dark"}),
    [](const auto& p) { return std::string(p.param.name); });

/// The tail study gives the same numbers, to the last bit, when run again with the same seed.
TEST(DiagnoseStatic, TailStudyIsDeterministic) {
  DiagnoseConfig dc;
  dc.replicas = 5;
  const StaticScans s = test::staticRoomWithTails(test::TailWhere::edge, 0.10, 0.05, 331);
  const auto a = diagnoseStatic(s, dc), b = diagnoseStatic(s, dc);
  ASSERT_TRUE(a.tails.fitted);
  EXPECT_EQ(a.primary_cause, b.primary_cause);
  EXPECT_EQ(a.tails.model, b.tails.model);
  EXPECT_EQ(a.tails.robust, b.tails.robust);
  EXPECT_EQ(a.tails.tail_readings_by_class, b.tails.tail_readings_by_class);
  ASSERT_EQ(a.tails.covariates.size(), b.tails.covariates.size());
  for (std::size_t k = 0; k < a.tails.covariates.size(); ++k)
    EXPECT_EQ(a.tails.covariates[k].unique_gain_nats_per_point,
              b.tails.covariates[k].unique_gain_nats_per_point);
  ASSERT_EQ(a.tails.top_beams.size(), b.tails.top_beams.size());
  for (std::size_t k = 0; k < a.tails.top_beams.size(); ++k)
    EXPECT_EQ(a.tails.top_beams[k].bearing_rad, b.tails.top_beams[k].bearing_rad);
}

}  // namespace
}  // namespace lidarcal::diagnosis
