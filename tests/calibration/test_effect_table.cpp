// SPDX-License-Identifier: BSD-3-Clause
// The one table of effects (common/effect.hpp) against the code that acts on them.

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "calibration/joint_refinement.hpp"
#include "common/effect.hpp"

namespace lidarcal {
namespace {

TEST(EffectTable, EveryEffectHasOneRowInEnumOrderAndItsNameParsesBack) {
  const auto& table = effectTable();
  std::set<std::string> names;
  for (std::size_t k = 0; k < table.size(); ++k) {
    const Effect e = static_cast<Effect>(k);
    EXPECT_EQ(table[k].effect, e) << k;
    EXPECT_EQ(&info(e), &table[k]);
    ASSERT_TRUE(parseEffect(toString(e)).has_value()) << toString(e);
    EXPECT_EQ(*parseEffect(toString(e)), e);
    names.insert(toString(e));
  }
  EXPECT_EQ(names.size(), table.size());
  EXPECT_EQ(toString(table.back().effect), std::string("dark_surface"));
  EXPECT_FALSE(parseEffect("none").has_value());
  EXPECT_FALSE(parseEffect("Incidence_noise").has_value());
  EXPECT_FALSE(parseEffect("").has_value());
}

TEST(EffectTable, TheJointRefinementHasATermExactlyForTheEffectsTheTableSays) {
  for (const auto& i : effectTable()) {
    calibration::JointEffects fx;
    fx.estimate_heading = false;
    const calibration::JointEffects before = fx;
    const bool has = fx.enable(i.effect);
    EXPECT_EQ(has, i.joint_term) << i.name;
    const bool changed =
        fx.estimate_heading != before.estimate_heading ||
        fx.landmark_offsets != before.landmark_offsets || fx.drift != before.drift ||
        fx.angle_offset != before.angle_offset || fx.incidence_bias != before.incidence_bias ||
        fx.incidence_noise != before.incidence_noise ||
        fx.noise_exponent != before.noise_exponent || fx.mixed_pixels != before.mixed_pixels ||
        fx.odometry_scale != before.odometry_scale || fx.student_noise != before.student_noise ||
        fx.quantised != before.quantised || fx.dark_noise != before.dark_noise;
    EXPECT_EQ(changed, has) << i.name;
    // A sequence can test exactly the effects the joint refinement can fit.
    EXPECT_EQ(i.sequence_statistic != nullptr, i.joint_term) << i.name;
  }
}

TEST(EffectTable, EffectNamesListsTheSelectedNamesInTableOrder) {
  EXPECT_EQ(
      effectNames([](const EffectInfo& i) { return i.static_statistic && !i.sequence_statistic; }),
      "");
  EXPECT_EQ(effectNames([](const EffectInfo& i) {
              return i.static_statistic && i.sequence_statistic && !i.joint_term;
            }),
            "");
  EXPECT_EQ(
      effectNames([](const EffectInfo& i) { return !i.static_statistic && !i.sequence_statistic; }),
      "");
  // Every effect is a candidate in both modes (dark_surface in static data too).
  EXPECT_EQ(
      effectNames([](const EffectInfo& i) { return !i.static_statistic || !i.sequence_statistic; }),
      "");
  // One pose shows nothing of stops, headings or one surface's offset: no static statistic.
  EXPECT_EQ(effectNames([](const EffectInfo& i) {
              return i.static_statistic && *i.static_statistic == '\0';
            }),
            "landmark_bias, heading_error, angle_offset, odometry_scale");
  EXPECT_EQ(effectNames([](const EffectInfo&) { return false; }), "");
}

}  // namespace
}  // namespace lidarcal
