// SPDX-License-Identifier: BSD-3-Clause
// The node's live poses without DDS (ros2::LivePoses): odometry composed with the sensor's mount,
// tf chains, interpolation to a scan's stamp against planar poses composed with
// lidarcal::compose, the missing link named, a bounded buffer, and received transforms that
// cannot be poses dropped by reason.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "ros2/live_poses.hpp"

namespace lidarcal::test {
namespace {

/// A planar transform (rotation about z by the pose's yaw) from `parent` to `child` at `sec` +
/// `nanosec`.
ros2::ReceivedTransform planar(const std::string& parent, const std::string& child,
                               std::int32_t sec, std::uint32_t nanosec, const Pose2& pose) {
  ros2::ReceivedTransform t;
  t.stamp = {sec, nanosec};
  t.parent = parent;
  t.child = child;
  t.x = pose.x_m;
  t.y = pose.y_m;
  t.qz = std::sin(pose.yaw_rad / 2);
  t.qw = std::cos(pose.yaw_rad / 2);
  return t;
}

ros2::LivePoseSettings source(ros2::PoseSource::Kind kind, const std::string& name) {
  ros2::LivePoseSettings s;
  s.source.kind = kind;
  s.source.name = name;
  return s;
}

void expectPose(const ros2::PoseLookup& got, const Pose2& want) {
  ASSERT_TRUE(got.pose) << got.why;
  EXPECT_NEAR(got.pose->x_m, want.x_m, 1e-9);
  EXPECT_NEAR(got.pose->y_m, want.y_m, 1e-9);
  EXPECT_NEAR(wrapAngle(got.pose->yaw_rad - want.yaw_rad), 0.0, 1e-9);
}

TEST(LivePoses, OdometryInterpolatedAndComposedWithTheMount) {
  ros2::LivePoses poses(source(ros2::PoseSource::Kind::odom, "/odom"));
  EXPECT_FALSE(poses.at("laser", {100, 0}).pose);
  EXPECT_NE(poses.at("laser", {100, 0}).why.find("no odometry message on /odom"),
            std::string::npos);
  EXPECT_FALSE(poses.addOdometry(planar("odom", "base_link", 100, 0, {1.0, 2.0, 0.0})));
  EXPECT_FALSE(poses.addOdometry(planar("odom", "base_link", 101, 0, {3.0, 2.0, 0.4})));
  // Without the mount the pose is base_link's, and the lookup says so.
  ros2::PoseLookup bare = poses.at("laser", {100, 500000000});
  expectPose(bare, {2.0, 2.0, 0.2});
  EXPECT_TRUE(bare.mount_missing);
  EXPECT_EQ(bare.fixed_frame, "odom");
  EXPECT_FALSE(poses.addTransform(planar("base_link", "laser", 1, 0, {0.2, 0.1, kPi / 2}), true));
  const ros2::PoseLookup mounted = poses.at("/laser", {100, 500000000});
  expectPose(mounted, compose(Pose2{2.0, 2.0, 0.2}, {0.2, 0.1, kPi / 2}));
  EXPECT_FALSE(mounted.mount_missing);
  // Held 0.1 s beyond the ends, not further: the reason names the span.
  EXPECT_TRUE(poses.at("laser", {101, 50000000}).pose);
  const ros2::PoseLookup late = poses.at("laser", {102, 0});
  EXPECT_FALSE(late.pose);
  EXPECT_NE(late.why.find("recorded from 100.000 to 101.000"), std::string::npos) << late.why;
  EXPECT_EQ(poses.stats().odometry, 2u);
  EXPECT_EQ(poses.stats().transforms, 1u);
}

TEST(LivePoses, TfChainToTheFixedFrameAndTheMissingLinkNamed) {
  ros2::LivePoses poses(source(ros2::PoseSource::Kind::tf, "map"));
  poses.addTransform(planar("map", "odom", 10, 0, {1.0, 2.0, 0.5}), false);
  poses.addTransform(planar("map", "odom", 12, 0, {1.0, 2.0, 0.5}), false);
  poses.addTransform(planar("odom", "base_link", 10, 0, {0.0, 0.0, 0.0}), false);
  poses.addTransform(planar("odom", "base_link", 12, 0, {4.0, 0.0, 1.0}), false);
  poses.addTransform(planar("base_link", "laser", 0, 1, {0.3, 0.0, kPi}), true);
  EXPECT_FALSE(poses.addOdometry(planar("odom", "base_link", 11, 0, {9.0, 9.0, 0.0})));  // ignored
  // At 11.5 s base_link is (3, 0, 0.75) in odom.
  const ros2::PoseLookup p = poses.at("laser", {11, 500000000});
  expectPose(p, compose(Pose2{1.0, 2.0, 0.5}, compose(Pose2{3.0, 0.0, 0.75}, {0.3, 0.0, kPi})));
  EXPECT_EQ(p.fixed_frame, "map");
  EXPECT_EQ(poses.stats().odometry, 0u);
  const ros2::PoseLookup camera = poses.at("camera", {11, 0});
  EXPECT_FALSE(camera.pose);
  EXPECT_NE(camera.why.find("'camera' is not connected to 'map'"), std::string::npos) << camera.why;
  poses.addTransform(planar("rear_mount", "rear_laser", 0, 1, {0.0, 0.0, 0.0}), true);
  const ros2::PoseLookup rear = poses.at("rear_laser", {11, 0});
  EXPECT_FALSE(rear.pose);
  EXPECT_NE(rear.why.find("the chain ends at 'rear_mount'"), std::string::npos) << rear.why;
  EXPECT_FALSE(poses.at("", {11, 0}).pose);
}

TEST(LivePoses, KeepsAShortBuffer) {
  ros2::LivePoseSettings s = source(ros2::PoseSource::Kind::odom, "/odom");
  s.window_s = 2.0;
  ros2::LivePoses poses(s);
  for (int k = 0; k <= 50; ++k)  // 10 Hz for 5 s
    poses.addOdometry(planar("odom", "base_link", 100 + k / 10,
                             static_cast<std::uint32_t>(k % 10) * 100000000u, {0.1 * k, 0.0, 0.0}));
  expectPose(poses.at("base_link", {104, 250000000}), {4.25, 0.0, 0.0});
  const ros2::PoseLookup old = poses.at("base_link", {101, 0});  // more than 2 s before the newest
  EXPECT_FALSE(old.pose);
  EXPECT_NE(old.why.find("recorded from 102.900 to 105.000"), std::string::npos) << old.why;
}

TEST(LivePoses, DropsWhatCannotBeAPoseByReason) {
  ros2::LivePoses poses(source(ros2::PoseSource::Kind::tf, "map"));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ros2::ReceivedTransform rotation_nan = planar("map", "base_link", 10, 0, {1.0, 0.0, 0.0});
  rotation_nan.qw = nan;
  ros2::ReceivedTransform infinite = planar("map", "base_link", 10, 0, {1.0, 0.0, 0.0});
  infinite.y = std::numeric_limits<double>::infinity();
  using R = ros2::PoseDropReason;
  const std::vector<std::pair<ros2::ReceivedTransform, R>> bad = {
      {planar("map", "base_link", 10, 1000000000u, {1.0, 0.0, 0.0}), R::bad_stamp},
      {planar("map", "base_link", 0, 0, {1.0, 0.0, 0.0}), R::bad_stamp},
      {planar("map", "base_link", -5, 0, {1.0, 0.0, 0.0}), R::bad_stamp},
      {planar("", "base_link", 10, 0, {1.0, 0.0, 0.0}), R::empty_frame},
      {planar("map", "/", 10, 0, {1.0, 0.0, 0.0}), R::empty_frame},
      {planar("map", "/map", 10, 0, {1.0, 0.0, 0.0}), R::self_transform},
      {planar("map", "base_link", 10, 0, {nan, 0.0, 0.0}), R::non_finite},
      {rotation_nan, R::non_finite},
      {infinite, R::non_finite},
  };
  for (const auto& [t, reason] : bad) {
    SCOPED_TRACE(ros2::toString(reason));
    EXPECT_EQ(poses.addTransform(t, false), reason);
  }
  EXPECT_EQ(poses.stats().droppedTotal(), bad.size());
  EXPECT_EQ(poses.stats().dropped[static_cast<std::size_t>(R::non_finite)], 3u);
  EXPECT_EQ(poses.stats().transforms, 0u);
  EXPECT_FALSE(poses.at("base_link", {10, 0}).pose);  // nothing of them was kept
  // An unset quaternion is the identity, as tf takes it; a scaled one is normalised.
  // A static transform may leave its stamp unset.
  ros2::ReceivedTransform zero = planar("map", "base_link", 0, 0, {1.0, 0.0, 0.0});
  zero.qw = 0.0;
  EXPECT_FALSE(poses.addTransform(zero, true));
  expectPose(poses.at("base_link", {10, 0}), {1.0, 0.0, 0.0});
  ros2::ReceivedTransform scaled = planar("map", "laser", 10, 0, {0.0, 0.0, 0.6});
  scaled.qz *= 3.0;
  scaled.qw *= 3.0;
  EXPECT_FALSE(poses.addTransform(scaled, true));
  expectPose(poses.at("laser", {10, 0}), {0.0, 0.0, 0.6});
}

}  // namespace
}  // namespace lidarcal::test
