// SPDX-License-Identifier: BSD-3-Clause
// Student's t distribution (common/student_t.hpp) against its closed forms (1 and 2 degrees of
// freedom), printed tables and the normal limit.

#include <cmath>

#include <gtest/gtest.h>

#include "common/student_t.hpp"

namespace lidarcal {
namespace {

TEST(StudentT, QuantilesMatchTheClosedFormsForOneAndTwoDegreesOfFreedom) {
  constexpr double kPi = 3.14159265358979323846;
  for (const double p : {0.01, 0.1, 0.3, 0.6, 0.8413, 0.975, 0.999}) {
    SCOPED_TRACE(p);
    EXPECT_NEAR(studentTQuantile(p, 1.0), std::tan(kPi * (p - 0.5)),
                1e-9 * (1.0 + std::abs(std::tan(kPi * (p - 0.5)))));
    const double two = (2.0 * p - 1.0) / std::sqrt(2.0 * p * (1.0 - p));
    EXPECT_NEAR(studentTQuantile(p, 2.0), two, 1e-9 * (1.0 + std::abs(two)));
  }
}

TEST(StudentT, QuantilesMatchPrintedTablesAndTheNormalLimit) {
  // Two-sided 95 % points of the t tables, and the normal's 1.959964.
  EXPECT_NEAR(centralTFactor(0.95, 1.0), 12.7062, 1e-4);
  EXPECT_NEAR(centralTFactor(0.95, 5.0), 2.5706, 1e-4);
  EXPECT_NEAR(centralTFactor(0.95, 16.0), 2.1199, 1e-4);
  EXPECT_NEAR(centralTFactor(0.95, 1e7), 1.959964, 1e-5);
  EXPECT_NEAR(centralTFactor(0.95, INFINITY), 1.959964, 1e-6);
  EXPECT_NEAR(centralTFactor(0.6827, INFINITY), 1.0, 1e-3);
}

TEST(StudentT, TheDistributionFunctionInvertsTheQuantileAndIsSymmetric) {
  for (const double dof : {0.5, 1.0, 3.0, 16.0, 200.0}) {
    for (const double p : {0.001, 0.2, 0.5, 0.7, 0.95}) {
      SCOPED_TRACE(dof);
      SCOPED_TRACE(p);
      const double t = studentTQuantile(p, dof);
      EXPECT_NEAR(studentTCdf(t, dof), p, 1e-10);
      EXPECT_NEAR(studentTCdf(-t, dof), 1.0 - p, 1e-10);
    }
  }
}

TEST(StudentT, InvalidArgumentsGiveNaN) {
  EXPECT_TRUE(std::isnan(studentTQuantile(0.0, 3.0)));
  EXPECT_TRUE(std::isnan(studentTQuantile(1.0, 3.0)));
  EXPECT_TRUE(std::isnan(studentTQuantile(0.5, 0.0)));
  EXPECT_TRUE(std::isnan(studentTCdf(1.0, -1.0)));
  EXPECT_TRUE(std::isnan(regularisedIncompleteBeta(1.0, 1.0, 1.5)));
  EXPECT_NEAR(regularisedIncompleteBeta(1.0, 1.0, 0.3), 0.3, 1e-14);  // the uniform distribution
}

}  // namespace
}  // namespace lidarcal
