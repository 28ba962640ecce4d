// SPDX-License-Identifier: BSD-3-Clause
// Holm's step-down adjustment against a hand computation.
#include <cmath>

#include <gtest/gtest.h>

#include "common/multiple_testing.hpp"

namespace lidarcal {
namespace {

TEST(MultipleTesting, HolmMatchesTheStepDownByHand) {
  // Sorted p: 0.01 (x4 = 0.04), 0.02 (x3 = 0.06), 0.03 (x2 = 0.06), 0.5 (x1 = 0.5).
  const auto adj = holmAdjust({0.03, 0.5, 0.01, 0.02});
  EXPECT_NEAR(adj[2], 0.04, 1e-12);
  EXPECT_NEAR(adj[3], 0.06, 1e-12);
  EXPECT_NEAR(adj[0], 0.06, 1e-12);  // monotone: max(0.06, 0.06)
  EXPECT_NEAR(adj[1], 0.5, 1e-12);
  const auto with_nan = holmAdjust({0.01, std::nan(""), 0.04});
  EXPECT_NEAR(with_nan[0], 0.02, 1e-12);
  EXPECT_TRUE(std::isnan(with_nan[1]));
  EXPECT_NEAR(with_nan[2], 0.04, 1e-12);
}

}  // namespace
}  // namespace lidarcal
