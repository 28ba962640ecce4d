// SPDX-License-Identifier: BSD-3-Clause
// Effects in a static recording named as the truth allows: readings rounded to a grid, mixed
// pixels at depth edges, an incidence exponent under contamination.

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

using test::staticRoom;
NoiseModel squared(double sigma_e) { return test::squaredNoise(sigma_e); }

/// Mixed pixels at 2-10 % of the edge readings (a fraction drawn per seed): the readings between
/// the two surfaces are tails on the edge beams, so mixed_pixels is named (by its own candidate, or
/// from the tails' edge covariate). Four seeds, at least 3. diagnoseStatic on staticRoom() with
/// `fx`, simulated and diagnosed with `seed`, 5 replicas.
DiagnosisResult diagnoseRoomAtSeed(const RangeEffects& fx, std::uint64_t seed) {
  DiagnoseConfig dc;
  dc.replicas = 5;
  dc.seed = seed;
  return diagnoseStatic(staticRoom(fx, squared(0.0015), seed), dc);
}

class ReadingGrid : public ::testing::TestWithParam<double> {};

TEST_P(ReadingGrid, ReadingsRoundedToItAreNamedQuantisation) {
  // Readings rounded to 2, 5 or 10 mm under noise of 3-50 mm (the room at 1.5-6 m). Every model is
  // scored on the readings spread uniformly over their grid cells, where the rounded model (a
  // normal cell probability over q) is the true one; a continuous model scored at the grid points,
  // or a variance floor, misses most 5 and 10 mm grids (docs/results/static-diagnosis.md). Four
  // rooms whose seeds come from a seed this test does not read (the method was developed on seeds
  // 101-130), at least 3 named.
  const double grid = GetParam();
  int right = 0;
  std::string log;
  for (const std::uint64_t seed : unreadSeeds(static_cast<std::uint64_t>(grid * 1e4), 4)) {
    RangeEffects fx;
    fx.range_resolution_m = grid;
    const auto r = diagnoseRoomAtSeed(fx, seed);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    right += names(r.primary_cause, Effect::quantisation);
    log += " seed " + std::to_string(seed) + ": " + r.primary_cause + ";";
  }
  std::printf("grid %.3f m:%s\n", grid, log.c_str());
  EXPECT_GE(right, 3) << "grid " << grid << ":" << log;
}

INSTANTIATE_TEST_SUITE_P(Room, ReadingGrid, ::testing::Values(0.002, 0.005, 0.010),
                         [](const auto& grid_info) {
                           return "mm" + std::to_string(
                                             static_cast<int>(std::lround(grid_info.param * 1e3)));
                         });

TEST(DiagnoseStatic, MixedPixelsAtTwoToTenPercentOfEdgeReadingsAreNamed) {
  int right = 0;
  std::string log;
  for (const std::uint64_t seed : unreadSeeds(321, 4)) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto rng = makeRng(seed, 5);
    RangeEffects fx;
    fx.mixed_pixel_fraction = 0.02 + 0.08 * u(rng);
    const auto r = diagnoseRoomAtSeed(fx, seed);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    right += names(r.primary_cause, Effect::mixed_pixels);
    char buf[200];
    std::snprintf(buf, sizeof buf, " seed %d (fraction %.3f): %s, tails %s;",
                  static_cast<int>(seed), fx.mixed_pixel_fraction, r.primary_cause.c_str(),
                  r.tails.cause.c_str());
    log += buf;
  }
  std::printf("mixed pixels:%s\n", log.c_str());
  EXPECT_GE(right, 3) << log;
}

/// Tails everywhere (5 % of all readings 5 cm off) over a noise growing as (1 / cos phi)^1: the
/// incidence exponent fitted under the contamination comes out near 1 (under the Gaussian
/// likelihood 0.73-0.88 on these seeds), and incidence_noise is named.
TEST(DiagnoseStatic, IncidenceExponentIsRecoveredUnderContamination) {
  RangeEffects fx;
  fx.incidence_noise_exponent = 1.0;
  for (std::uint64_t seed = 311; seed < 314; ++seed) {
    SCOPED_TRACE(seed);
    DiagnoseConfig dc;
    dc.replicas = 5;
    dc.seed = seed;
    const auto r = diagnoseStatic(
        test::staticRoomWithTails(test::TailWhere::everywhere, 0.05, 0.05, seed, fx), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    ASSERT_TRUE(r.tails.fitted) << r.tails.note;
    const double robust = r.tails.robust.at("incidence_noise_exponent");
    double gaussian = std::numeric_limits<double>::quiet_NaN();
    for (const auto& k : r.candidates)
      if (k.effect == Effect::incidence_noise)
        gaussian = k.estimates.at("incidence_noise_exponent");
    std::printf(
        "seed %d: incidence exponent %.3f under the contamination, %.3f under the Gaussian; named "
        "%s; robust gains: "
        "gamma %.4f +- %.4f, kappa %.4f +- %.4f\n",
        static_cast<int>(seed), robust, gaussian, r.primary_cause.c_str(),
        r.tails.robust.at("incidence_noise_exponent_gain"),
        r.tails.robust.at("incidence_noise_exponent_gain_se"),
        r.tails.robust.at("noise_exponent_gain"), r.tails.robust.at("noise_exponent_gain_se"));
    EXPECT_NEAR(robust, 1.0, 0.15);
    // The Gaussian ranking, dominated by the tails, puts a range law first; ranked beside the
    // contamination the incidence noise comes first.
    EXPECT_EQ(r.primary_cause, "incidence_noise")
        << r.decision << " tails significant " << r.tails.significant << " p " << r.tails.p_value;
    EXPECT_GT(r.tails.robust.at("incidence_noise_exponent_gain"), 0.0);
  }
}

}  // namespace
}  // namespace lidarcal::diagnosis
