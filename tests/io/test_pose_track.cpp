// SPDX-License-Identifier: BSD-3-Clause
// Poses looked up at scan stamps (import --pose): interpolation against closed forms, tf chains
// against composing by hand, the still-pose filter's stops.

#include <cmath>

#include <gtest/gtest.h>

#include "io/pose_track.hpp"

namespace lidarcal::io {
namespace {

Transform3 planar(double x, double y, double yaw) {
  Transform3 t;
  t.translation = {x, y, 0.0};
  t.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return t;
}

TEST(TransformTrack, InterpolatesLinearlyAndBySlerp) {
  TransformTrack track;
  track.add(12.0, planar(3.0, -1.0, 0.9));  // out of order on purpose
  track.add(10.0, planar(1.0, 1.0, 0.1));
  for (double u : {0.0, 0.25, 0.5, 0.8, 1.0}) {
    SCOPED_TRACE(u);
    const auto t = track.at(10.0 + 2.0 * u, 0.0);
    ASSERT_TRUE(t);
    const Pose2 p = planarPose(*t);
    EXPECT_NEAR(p.x_m, 1.0 + 2.0 * u, 1e-12);
    EXPECT_NEAR(p.y_m, 1.0 - 2.0 * u, 1e-12);
    EXPECT_NEAR(p.yaw_rad, 0.1 + 0.8 * u, 1e-12);  // slerp about one axis: the angle is linear
  }
}

TEST(TransformTrack, HoldsTheEndsOnlyWithinTheHoldTime) {
  TransformTrack track;
  track.add(10.0, planar(1.0, 0.0, 0.0));
  track.add(11.0, planar(2.0, 0.0, 0.0));
  EXPECT_TRUE(track.at(9.95, 0.1));
  EXPECT_FALSE(track.at(9.85, 0.1));
  EXPECT_TRUE(track.at(11.05, 0.1));
  EXPECT_FALSE(track.at(11.2, 0.1));
  EXPECT_FALSE(track.at(std::nan(""), 1.0));
  EXPECT_FALSE(TransformTrack().at(10.0, 1.0));
}

TEST(TransformTrack, KeepsTheWindowAndTheSampleBeforeIt) {
  TransformTrack track;
  for (int k = 0; k <= 20; ++k)
    track.add(static_cast<double>(k), planar(static_cast<double>(k), 0.0, 0.0));
  track.keepWithin(5.5, 1000);  // newest 20: the window starts at 14.5, the sample at 14 stays
  EXPECT_EQ(track.size(), 7u);
  EXPECT_EQ(track.span().first, 14.0);
  const auto mid = track.at(14.75, 0.0);  // still interpolates at the window's start
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->translation.x(), 14.75, 1e-12);
  EXPECT_FALSE(track.at(13.0, 0.1));  // forgotten
  track.keepWithin(100.0, 3);         // then by count
  EXPECT_EQ(track.size(), 3u);
  EXPECT_EQ(track.span(), std::make_pair(18.0, 20.0));
  track.keepWithin(0.0, 0);  // never below two samples
  EXPECT_EQ(track.size(), 2u);
}

TEST(TransformTree, ComposesTheChainToTheFixedFrame) {
  TransformTree tree;
  tree.addDynamic("map", "odom", 0.0, planar(1.0, 2.0, 0.5));
  tree.addDynamic("map", "odom", 10.0, planar(1.0, 2.0, 0.5));
  tree.addDynamic("odom", "base", 0.0, planar(0.0, 0.0, 0.0));
  tree.addDynamic("odom", "base", 10.0, planar(5.0, 0.0, 1.0));
  tree.addStatic("base", "laser", planar(0.3, 0.1, kPi));
  const auto t = tree.lookup("map", "laser", 4.0, 0.0);
  ASSERT_TRUE(t);
  // By hand: base in odom at 4 s is (2, 0, 0.4); laser = map<-odom * odom<-base * base<-laser.
  Pose2 base{2.0, 0.0, 0.4};
  double bx, by;
  base.toWorld(0.3, 0.1, bx, by);
  Pose2 odom{1.0, 2.0, 0.5};
  double x, y;
  odom.toWorld(bx, by, x, y);
  const Pose2 p = planarPose(*t);
  EXPECT_NEAR(p.x_m, x, 1e-12);
  EXPECT_NEAR(p.y_m, y, 1e-12);
  EXPECT_NEAR(wrapAngle(p.yaw_rad - (0.5 + 0.4 + kPi)), 0.0, 1e-12);
  EXPECT_FALSE(isUpsideDown(*t));
  std::string why;
  EXPECT_FALSE(tree.lookup("map", "laser", 11.0, 0.1, &why));
  EXPECT_NE(why.find("odom -> base"), std::string::npos) << why;
  EXPECT_FALSE(tree.lookup("world", "laser", 4.0, 0.0, &why));
  EXPECT_NE(why.find("not connected"), std::string::npos) << why;
  EXPECT_TRUE(tree.lookup("laser", "laser", 4.0, 0.0));  // a frame in itself: identity
}

TEST(TransformTree, UpsideDownMount) {
  TransformTree tree;
  Transform3 flipped = planar(0.5, 0.0, 0.0);
  flipped.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()));
  tree.addStatic("base", "laser", flipped);
  const auto t = tree.lookup("base", "laser", 0.0, 0.0);
  ASSERT_TRUE(t);
  EXPECT_TRUE(isUpsideDown(*t));
  EXPECT_NEAR(planarPose(*t).yaw_rad, 0.0, 1e-12);  // x axis still forward
}

TEST(StillPoseFilter, HoldsThePoseOfEachStop) {
  StillPoseFilter f(0.01, deg2rad(0.5));
  const Pose2 a = f.apply({1.0, 1.0, 0.2});
  EXPECT_EQ(f.apply({1.004, 0.997, 0.2 + deg2rad(0.3)}).x_m, a.x_m);  // jitter: same pose
  const Pose2 moved = f.apply({1.05, 1.0, 0.2});
  EXPECT_EQ(moved.x_m, 1.05);
  const Pose2 turned = f.apply({1.05, 1.0, 0.2 + deg2rad(1.0)});
  EXPECT_NEAR(turned.yaw_rad, 0.2 + deg2rad(1.0), 1e-15);
  EXPECT_EQ(f.stops(), 3u);
  // Wrap-around: -pi and +pi are the same heading.
  StillPoseFilter w(0.01, 0.01);
  w.apply({0.0, 0.0, kPi - 0.001});
  EXPECT_EQ(w.apply({0.0, 0.0, -kPi + 0.001}).yaw_rad, kPi - 0.001);
}

}  // namespace
}  // namespace lidarcal::io
