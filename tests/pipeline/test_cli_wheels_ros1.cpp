// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal import BAG.bag --wheels TOPIC:LEFT,RIGHT` on a ROS1 bag written with the ROS
// libraries: each wheel's angle at each scan's stamp in SEQ/wheel_angles.csv, interpolated
// between the sensor_msgs/JointState messages around it.

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include <rosbag/bag.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/LaserScan.h>

#include "io/wheel_angles_csv.hpp"
#include "ros/laser_scan_util.hpp"
#include "test_util.hpp"

namespace lidarcal::test {
namespace {

double leftAt(double t) { return 0.5 - 1.5 * (t - 100.0); }
double rightAt(double t) { return 4.0 * (t - 100.0); }

TEST(CliWheelsRos1, EachScansWheelAnglesAreInterpolatedAtItsStamp) {
  TempDir dir;
  const std::filesystem::path file = dir / "drive.bag";
  {
    rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
    for (int k = 0; k < 6; ++k) {
      const sensor_msgs::LaserScan m = laserScan(k, 100);
      bag.write("/scan", m.header.stamp, m);
    }
    for (double t = 99.9; t < 105.5; t += 0.25) {
      sensor_msgs::JointState j;
      j.header.stamp = ros::Time(t);
      j.name = {"right", "left"};
      j.position = {rightAt(t), leftAt(t)};
      bag.write("/joint_states", j.header.stamp, j);
    }
    bag.close();
  }
  const auto r = runCli("import " + file.string() + " -o " + (dir / "seq").string() +
                        " --wheels /joint_states:left,right");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = io::readWheelAnglesCsv(dir / "seq" / "wheel_angles.csv");
  ASSERT_EQ(rows.size(), 6u);
  for (int k = 0; k < 6; ++k) {
    const double t = ros::Time(100 + k, 1000 * k).toSec();
    EXPECT_NEAR(rows[k].left_rad, leftAt(t), 1e-6) << k;
    EXPECT_NEAR(rows[k].right_rad, rightAt(t), 1e-6) << k;
  }
}

}  // namespace
}  // namespace lidarcal::test
