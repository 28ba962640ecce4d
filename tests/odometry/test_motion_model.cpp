// SPDX-License-Identifier: BSD-3-Clause
// The motion model: the arc of a differential drive, the laser displacement it implies, and the
// analytic Jacobian against central differences.

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/pose2.hpp"
#include "common/rng.hpp"
#include "odometry/motion_model.hpp"

namespace lidarcal::odometry {
namespace {

const OdometryParameters kRobot{0.0206, 0.0207, 0.088, -0.0026, 0.0058, -1.558};

OdometrySample wheels(double left, double right, double duration = 0.8) {
  OdometrySample s;
  s.duration_s = duration;
  s.left_wheel_rad_s = left;
  s.right_wheel_rad_s = right;
  return s;
}

TEST(MotionModel, StraightDrivingMovesTheRobotAlongItsAxis) {
  const OdometrySample s = wheels(0.5, 0.5);
  const double r = 0.021;
  const Eigen::Vector3d d = robotDisplacement(r, r, 0.09, s);
  EXPECT_NEAR(d[0], r * 0.5 * 0.8, 1e-15);
  EXPECT_EQ(d[1], 0.0);
  EXPECT_EQ(d[2], 0.0);
}

TEST(MotionModel, TurningInPlaceMovesTheLaserOnACircleAboutTheAxleCentre) {
  // Both wheels at opposite speeds: the robot turns about its origin by 2 r phi T / b.
  const OdometryParameters p{0.02, 0.02, 0.1, 0.05, 0.0, kPi / 2};
  const OdometrySample s = wheels(-0.5, 0.5, 1.0);
  const double turn = 2.0 * 0.02 * 0.5 / 0.1;
  // The laser sits at (0.05, 0) facing +y; after the turn it is at 0.05 (cos, sin)(turn)
  // facing +y+turn. Its displacement in its own start frame: rotate by -pi/2.
  const Pose2 start{0.05, 0.0, kPi / 2},
      end{0.05 * std::cos(turn), 0.05 * std::sin(turn), kPi / 2 + turn};
  const Pose2 expected = stepBetween(start, end);
  const Eigen::Vector3d d = predictedScanMatch(p, s);
  EXPECT_NEAR(d[0], expected.x_m, 1e-15);
  EXPECT_NEAR(d[1], expected.y_m, 1e-15);
  EXPECT_NEAR(d[2], turn, 1e-15);
}

TEST(MotionModel, TheLaserDisplacementIsTheRobotArcSeenFromTheMounting) {
  // Oracle: compose the poses with common/pose2.hpp: laser end = robot end (+) mounting.
  const OdometrySample s = wheels(0.3, 0.6);
  const Eigen::Vector3d r =
      robotDisplacement(kRobot.left_radius_m, kRobot.right_radius_m, kRobot.axle_m, s);
  const Pose2 mount{kRobot.laser_x_m, kRobot.laser_y_m, kRobot.laser_theta_rad};
  const Pose2 laser_end = compose(Pose2{r[0], r[1], r[2]}, mount);
  const Pose2 expected = stepBetween(mount, laser_end);
  const Eigen::Vector3d d = predictedScanMatch(kRobot, s);
  EXPECT_NEAR(d[0], expected.x_m, 1e-15);
  EXPECT_NEAR(d[1], expected.y_m, 1e-15);
  EXPECT_NEAR(d[2], expected.yaw_rad, 1e-15);
}

TEST(MotionModel, TheArcFactorsSeriesAgreesWithTheClosedForm) {
  // Oracle: the textbook expressions, where they are still accurate (just inside the series).
  for (const double a : {0.9 * kArcSeriesBelow, -0.5 * kArcSeriesBelow, 1e-3}) {
    double f, g;
    arcFactors(a, f, g);
    EXPECT_NEAR(f, std::sin(a) / a, 1e-15);
    EXPECT_NEAR(g, (1.0 - std::cos(a)) / a, 1e-13);  // 1 - cos a loses digits, not the series
  }
  double f, g;
  arcFactors(0.0, f, g);
  EXPECT_EQ(f, 1.0);
  EXPECT_EQ(g, 0.0);
}

/// Central differences of predictedScanMatch, step scaled to each parameter.
Jacobian numericJacobian(const OdometryParameters& p, const OdometrySample& s) {
  Jacobian j;
  const Vector6 x = p.toVector();
  for (int k = 0; k < kParameterCount; ++k) {
    const double h = 1e-6 * std::max(std::abs(x[k]), 1e-2);
    Vector6 plus = x, minus = x;
    plus[k] += h;
    minus[k] -= h;
    j.col(k) = (predictedScanMatch(OdometryParameters::fromVector(plus), s) -
                predictedScanMatch(OdometryParameters::fromVector(minus), s)) /
               (2.0 * h);
  }
  return j;
}

TEST(MotionModel, TheJacobianMatchesCentralDifferences) {
  std::mt19937_64 rng = makeRng(7, 0);
  std::uniform_real_distribution<double> speed(-0.7, 0.7), unit(0.0, 1.0);
  std::vector<OdometrySample> cases = {wheels(0.5, 0.5), wheels(-0.5, 0.5), wheels(0.4, 0.0),
                                       wheels(0.0, 0.0), wheels(0.5, 0.5 + 1e-9)};
  for (int k = 0; k < 200; ++k) cases.push_back(wheels(speed(rng), speed(rng), 0.5 + unit(rng)));
  for (std::size_t c = 0; c < cases.size(); ++c) {
    SCOPED_TRACE(c);
    OdometryParameters p = kRobot;
    p.laser_theta_rad = -3.0 + 6.0 * unit(rng);
    p.laser_x_m = 0.2 * (unit(rng) - 0.5);
    const Jacobian analytic = predictedScanMatchJacobian(p, cases[c]);
    const Jacobian numeric = numericJacobian(p, cases[c]);
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < kParameterCount; ++col)
        EXPECT_NEAR(analytic(row, col), numeric(row, col),
                    1e-6 * std::max(1.0, std::abs(numeric(row, col))))
            << "row " << row << " col " << col;
  }
}

TEST(MotionModel, TheJacobianHoldsOnBothSidesOfTheArcSeries) {
  // Turns of 0 and 5e-3 rad use the series, 2e-2 rad the closed form: each derivative must
  // match central differences there (a wrong series term shows near straight driving only).
  OdometryParameters p = kRobot;
  p.right_radius_m = p.left_radius_m;
  for (const double turn : {0.0, 1e-6, 5e-3, 2e-2}) {
    SCOPED_TRACE(turn);
    // right - left = turn b / (r T) with the left wheel at 0.5 rad/s
    const OdometrySample s = wheels(0.5, 0.5 + turn * p.axle_m / (p.left_radius_m * 0.8));
    const Jacobian analytic = predictedScanMatchJacobian(p, s);
    const Jacobian numeric = numericJacobian(p, s);
    for (int col = 0; col < kParameterCount; ++col)
      for (int row = 0; row < 3; ++row)
        EXPECT_NEAR(analytic(row, col), numeric(row, col),
                    1e-7 * std::max(1.0, std::abs(numeric(row, col))))
            << "row " << row << " col " << col;
  }
}

TEST(MotionModel, TheResidualIsMeasuredMinusPredicted) {
  OdometrySample s = wheels(0.2, 0.4);
  const Eigen::Vector3d d = predictedScanMatch(kRobot, s);
  s.scan_match_x_m = d[0] + 0.001;
  s.scan_match_y_m = d[1] - 0.002;
  s.scan_match_theta_rad = d[2] + 0.003;
  const Eigen::Vector3d e = scanMatchResidual(kRobot, s);
  EXPECT_NEAR(e[0], 0.001, 1e-15);
  EXPECT_NEAR(e[1], -0.002, 1e-15);
  EXPECT_NEAR(e[2], 0.003, 1e-15);
}

TEST(MotionModel, ParametersRoundTripThroughTheirVector) {
  const OdometryParameters back = OdometryParameters::fromVector(kRobot.toVector());
  EXPECT_EQ(back.toVector(), kRobot.toVector());
  EXPECT_EQ(kRobot.toVector()[2], kRobot.axle_m);
  EXPECT_STREQ(kParameterNames[5], "laser_theta_rad");
}

}  // namespace
}  // namespace lidarcal::odometry
