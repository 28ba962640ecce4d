// SPDX-License-Identifier: BSD-3-Clause
// Numbers as text (common/number_text.hpp): the forms the reports print.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "common/number_text.hpp"

namespace lidarcal {
namespace {

TEST(NumberText, FixedWritesDecimalsAndASignWhenAsked) {
  EXPECT_EQ(fixed(3.14159, 2), "3.14");
  EXPECT_EQ(fixed(2.5, 1, true), "+2.5");
  EXPECT_EQ(fixed(-2.5, 1, true), "-2.5");
}

TEST(NumberText, FixedOrDashLeavesACellWithoutAValueAsADash) {
  EXPECT_EQ(fixedOrDash(12.345, 1), "12.3");
  EXPECT_EQ(fixedOrDash(0.5, 2, true), "+0.50");
  EXPECT_EQ(fixedOrDash(std::nan(""), 1), "-");
  EXPECT_EQ(fixedOrDash(std::numeric_limits<double>::infinity(), 1, true), "-");
}

TEST(NumberText, FormattedHoldsTextOfAnyLength) {
  const std::string long_text(500, 'x');
  EXPECT_EQ(formatted("%s|%d", long_text.c_str(), 7), long_text + "|7");
  EXPECT_EQ(significant(1234.5678, 3), "1.23e+03");
}

}  // namespace
}  // namespace lidarcal
