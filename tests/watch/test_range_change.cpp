// SPDX-License-Identifier: BSD-3-Clause
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "watch/false_alarms.hpp"
#include "watch/range_change.hpp"

namespace lidarcal::watch {
namespace {

TEST(RangeChange, ParsesOffsetsScalesAndBoth) {
  RangeChange c = parseRangeChange("20@300");
  EXPECT_DOUBLE_EQ(c.offset_m, 0.020);
  EXPECT_DOUBLE_EQ(c.scale, 0.0);
  EXPECT_EQ(c.from_scan, 300u);
  c = parseRangeChange("0.3%@0");
  EXPECT_DOUBLE_EQ(c.scale, 0.003);
  EXPECT_EQ(c.from_scan, 0u);
  c = parseRangeChange("-10+1%@5");
  EXPECT_DOUBLE_EQ(c.offset_m, -0.010);
  EXPECT_DOUBLE_EQ(c.scale, 0.01);
  for (const char* bad : {"20", "@5", "20@", "x@5", "20@-1", "20@1.5", "20+@5", "20@5x"})
    EXPECT_THROW(parseRangeChange(bad), std::invalid_argument) << bad;
}

TEST(RangeChange, ChangesReturnsFromItsScanOnAndLeavesTheRest) {
  const RangeChange c = parseRangeChange("20+1%@3");
  io::RawScan s;
  s.ranges_m = {1.0f, std::numeric_limits<float>::quiet_NaN(), 0.0f, 2.0f};
  io::RawScan before = s;
  applyChange(c, 2, before);
  EXPECT_EQ(before.ranges_m[0], 1.0f);
  applyChange(c, 3, s);
  EXPECT_FLOAT_EQ(s.ranges_m[0], 1.03f);
  EXPECT_TRUE(std::isnan(s.ranges_m[1]));
  EXPECT_EQ(s.ranges_m[2], 0.0f);  // no return stays no return
  EXPECT_FLOAT_EQ(s.ranges_m[3], 2.04f);
}

TEST(FalseAlarmBudget, SpendsTheRateTimesTheExposureOfEachDecision) {
  FalseAlarmBudget km(FalseAlarmRate{0.5, Exposure::distance});
  km.expose(0.002, 1.0);  // 2 m, an hour: counted in km
  km.expose(0.004, 1.0);
  EXPECT_NEAR(km.spend(), 0.5 * 0.006, 1e-15);
  EXPECT_EQ(km.pending(), 0.0);
  FalseAlarmBudget hours(FalseAlarmRate{2.0, Exposure::time});
  hours.expose(5.0, 0.01);
  EXPECT_NEAR(hours.spend(), 0.02, 1e-15);
  hours.expose(0.0, 10.0);  // a long gap spends at most kMaxLevel
  EXPECT_EQ(hours.spend(), kMaxLevel);
}

}  // namespace
}  // namespace lidarcal::watch
