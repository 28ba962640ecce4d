// SPDX-License-Identifier: BSD-3-Clause
// The static diagnosis (diagnosis/static_scene.hpp) on a simulated room seen from one pose: a clean
// room has no cause and its walls are found, a hidden effect is named as the truth allows, a
// turning sensor is diagnosed in windows, progress changes nothing, and data it cannot diagnose
// give a status.

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
#include "io/scene_io.hpp"
#include "simulation/simulator.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

using test::staticRoom;
NoiseModel squared(double sigma_e) { return test::squaredNoise(sigma_e); }

TEST(DiagnoseStatic, CleanRoomHasNoCauseAndFindsItsWalls) {
  DiagnoseConfig dc;
  dc.replicas = 9;
  std::vector<WallLine> walls;
  const auto r = diagnoseStatic(staticRoom({}, squared(0.0015), 3), dc, &walls);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  EXPECT_EQ(r.mode, DiagnoseMode::static_scene);
  EXPECT_EQ(r.primary_cause, cause::kNone) << r.decision;
  EXPECT_GE(walls.size(), 4u);
  EXPECT_NEAR(r.baseline_extra.at("alpha0_m"), 0.01,
              4.0 * r.baseline_extra.at("alpha0_se_m") + 0.002);
  EXPECT_NEAR(r.baseline.noise.sigma_e, 0.0015, 0.0002);
  for (const auto& c : r.candidates) {
    if (c.effect == Effect::heading_error || c.effect == Effect::angle_offset) {
      EXPECT_FALSE(c.applicable);
    }
  }
}

class StaticHiddenEffect : public ::testing::TestWithParam<test::StaticCase> {};

TEST_P(StaticHiddenEffect, DiagnoseNamesWhatTheTruthAllows) {
  const test::StaticCase& c = GetParam();
  DiagnoseConfig dc;
  dc.replicas = 9;
  dc.static_range_offset_m = c.known_offset_m;
  // One room whose seed comes from a seed this test does not read (the rates over seeds:
  // docs/results/static-diagnosis.md).
  const std::uint64_t seed = unreadSeeds(nameTag(c.name), 1).front();
  dc.seed = seed;
  const auto r = diagnoseStatic(staticRoom(c, seed), dc);
  SCOPED_TRACE(seed);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  if (!c.also.empty()) {
    EXPECT_TRUE(c.allows(r.primary_cause)) << r.primary_cause << ": " << r.decision;
  } else {
    EXPECT_EQ(r.primary_cause, c.effect) << r.decision;
  }
  for (const auto& k : r.candidates) {
    if (k.effect == Effect::heading_error || k.effect == Effect::angle_offset ||
        k.effect == Effect::odometry_scale) {
      EXPECT_FALSE(k.applicable) << toString(k.effect);  // one pose: no stops, no headings
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Room, StaticHiddenEffect, ::testing::ValuesIn(test::staticCases()),
                         [](const auto& p) { return std::string(p.param.name); });

TEST(DiagnoseStatic, ATurningSensorIsDiagnosedInWindowsAndItsEdgesNamed) {
  // The sensor turns in place by 0.05 degree per scan (3 degrees over the recording); its readings
  // follow the seeds' model exactly. The diagnosis sees the motion (windows of 8 scans, each with a
  // time trend per beam), and what the motion does to the data: a beam that sweeps across the
  // pillar's or the box's edge within a window reads now the near, now the far surface, which is
  // what the mixed-pixel candidate describes. No range effect of the sensor may be named.
  const StaticScans s = staticRoom({}, squared(0.0015), 5, 64, 0.0, deg2rad(0.05));
  DiagnoseConfig dc;
  dc.replicas = 5;
  const auto r = diagnoseStatic(s, dc);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  EXPECT_EQ(r.baseline_extra.at("window_scans"), 8.0);
  EXPECT_EQ(r.primary_cause, toString(Effect::mixed_pixels)) << r.decision;
}

TEST(DiagnoseStatic, ADriftIsSimulatedOnTheFitsConventionFromItsSceneKeys) {
  // The fit centres the drift on the mean scan; the scene keys that simulate it say so
  // (range_drift_reference_scan) instead of moving alpha_0, and the extended simulation, which
  // uses them, comes closer to the data than the baseline's.
  RangeEffects fx;
  fx.range_drift_m_per_scan = 2e-4;
  const int scans = 150;
  DiagnoseConfig dc;
  dc.replicas = 9;
  const auto r = diagnoseStatic(staticRoom(fx, squared(0.0015), 7, scans), dc);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  ASSERT_EQ(r.primary_cause, toString(Effect::range_drift)) << r.decision;
  ASSERT_TRUE(r.scene_keys.count("sensor.effects.range_drift_reference_scan"));
  EXPECT_NEAR(r.scene_keys.at("sensor.effects.range_drift_reference_scan"), (scans - 1) / 2.0, 1.0);
  EXPECT_NEAR(r.scene_keys.at("sensor.effects.range_drift_m_per_scan"), 2e-4, 4e-5);
  EXPECT_LT(r.closeness_extended.variance_ratio_median_abs_log,
            r.closeness_baseline.variance_ratio_median_abs_log);
}

TEST(DiagnoseStatic, ProgressHearsEveryStepAndChangesNothing) {
  DiagnoseConfig dc;
  dc.replicas = 5;
  const diagnosis::StaticScans s = staticRoom({}, squared(0.0015), 3, 60);
  const auto quiet = diagnoseStatic(s, dc);
  std::vector<std::string> stages;
  std::size_t replicas_done = 0;
  dc.progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
    if (stages.empty() || stages.back() != stage) stages.push_back(stage);
    if (stage == "bootstrap replicas") {
      EXPECT_EQ(total, 5u);
      replicas_done = std::max(replicas_done, done);
    }
    EXPECT_TRUE(total == 0 || done <= total) << stage;
  };
  const auto heard = diagnoseStatic(s, dc);
  EXPECT_EQ(stages, (std::vector<std::string>{"baseline fit", "bootstrap replicas", "held-out fits",
                                              "candidate tests", "extended model"}));
  EXPECT_EQ(replicas_done, 5u);
  EXPECT_EQ(heard.primary_cause, quiet.primary_cause);
  EXPECT_EQ(heard.baseline_heldout_nats_per_point, quiet.baseline_heldout_nats_per_point);
  EXPECT_EQ(heard.gain_heldout_nats_per_point, quiet.gain_heldout_nats_per_point);
}

/// Static clean-room runs over many seeds (LIDARCAL_STATIC_CLEAN_SEEDS; the long run registers 20):
/// how often clean data get a cause. Skipped when the variable is unset.
TEST(DiagnoseStatic, CleanRoomFalsePositiveRateOverSeeds) {
  const char* env = std::getenv("LIDARCAL_STATIC_CLEAN_SEEDS");
  const int n = env && *env ? std::atoi(env) : 0;
  if (n <= 0) GTEST_SKIP() << "set LIDARCAL_STATIC_CLEAN_SEEDS (ctest -L long runs 20)";
  int named = 0;
  std::string which;
  for (int seed = 101; seed < 101 + n; ++seed) {
    DiagnoseConfig dc;
    dc.seed = static_cast<std::uint64_t>(seed);
    const auto r =
        diagnoseStatic(staticRoom({}, squared(0.0015), static_cast<std::uint64_t>(seed)), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    if (r.primary_cause != cause::kNone) {
      ++named;
      which += " seed " + std::to_string(seed) + ": " + r.primary_cause + ";";
    }
  }
  std::printf("static clean room: a cause named in %d of %d seeds;%s\n", named, n, which.c_str());
  // Holm at alpha = 0.01 over the candidates: at most 1 % of clean recordings should get a cause.
  // Allowance: at most 1 in 20 (a method at exactly 1 % exceeds it with probability 1.7 %).
  EXPECT_LE(named, std::max(1, n / 20)) << which;
}

/// One pose in front of `walls` (and `poles`) only: the room's sensor with 0.25-degree beams.
StaticScans sceneOf(std::vector<Segment> walls, std::vector<Cylinder> poles, std::uint64_t seed) {
  Scene s = test::staticRoomScene({}, squared(0.0015), 60, 0.0);
  s.sensor.beams = 1440;
  s.sensor.angle_increment_rad = deg2rad(0.25);
  s.walls = std::move(walls);
  s.clutter = std::move(poles);
  return test::sceneScans(s, seed);
}

TEST(DiagnoseStatic, OneTargetAloneIsRefusedAndOneLongWallIsNot) {
  // Scans masked to one target, as the Hokuyo range sweep is (a reflector, nothing else), or a
  // short board: enough beams return, but over a few degrees, with no spread in range or
  // incidence to read an effect off.
  DiagnoseConfig dc;
  dc.replicas = 5;
  for (const auto& [what, scans] :
       {std::pair{"a pole 0.9 m away", sceneOf({}, {{1.0, 0.3, 0.045}}, 3)},
        std::pair{"a 0.2 m board 1.7 m away", sceneOf({{2.0, -0.1, 2.0, 0.1}}, {}, 4)}}) {
    SCOPED_TRACE(what);
    const auto r = diagnoseStatic(scans, dc);
    EXPECT_STREQ(r.status.name(), "too_few_walls")
        << r.status.message << " cause " << r.primary_cause;
    // says what to record
    EXPECT_NE(r.status.message.find("room"), std::string::npos) << r.status.message;
  }
  // One wall 1.7 m away across 120 degrees of the view is enough.
  const auto wall = diagnoseStatic(sceneOf({{2.0, -3.0, 2.0, 3.0}}, {}, 5), dc);
  EXPECT_TRUE(wall.status.ok()) << wall.status.name() << ": " << wall.status.message;
  EXPECT_EQ(wall.landmarks, 1u);
}

TEST(DiagnoseStatic, TooFewScansGiveAStatus) {
  const auto r = diagnoseStatic(staticRoom({}, squared(0.0015), 1, 3), DiagnoseConfig{});
  EXPECT_STREQ(r.status.name(), "too_few_scans");
  EXPECT_FALSE(r.status.message.empty());
}

}  // namespace
}  // namespace lidarcal::diagnosis
