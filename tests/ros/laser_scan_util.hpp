// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A synthetic sensor_msgs/LaserScan for the bag and node tests (ROS headers: only test targets
// built with the ROS libraries include this).

#include <cstddef>
#include <cstdint>
#include <limits>

#include <cmath>

#include <gtest/gtest.h>
#include <sensor_msgs/LaserScan.h>

namespace lidarcal::test {

/// A LaserScan of n beams in frame "laser" stamped `stamp`: angles from -3.1 rad by `increment`,
/// limits 0.15-12 m, reading i = range(i), intensity i = intensity(i) (none when intensity_mod 0:
/// i mod intensity_mod otherwise).
template <class Range>
sensor_msgs::LaserScan laserScanOf(ros::Time stamp, std::size_t n, float increment, Range range,
                                   unsigned intensity_mod) {
  sensor_msgs::LaserScan m;
  m.header.stamp = stamp;
  m.header.frame_id = "laser";
  m.angle_min = -3.1f;
  m.angle_increment = increment;
  m.angle_max = m.angle_min + m.angle_increment * static_cast<float>(n - 1);
  m.range_min = 0.15f;
  m.range_max = 12.0f;
  for (std::size_t i = 0; i < n; ++i) {
    m.ranges.push_back(range(i));
    if (intensity_mod != 0) m.intensities.push_back(static_cast<float>(i % intensity_mod));
  }
  return m;
}

/// Scan k of n beams: readings 0.2 + 0.11 i + 0.01 k metres (0.2-11.1 m for 100 beams),
/// intensities i mod 7; beams 1-5 hold what is not a reading: inf, NaN, 0, below range_min,
/// above range_max.
inline sensor_msgs::LaserScan laserScan(int k, std::size_t n) {
  sensor_msgs::LaserScan m = laserScanOf(
      ros::Time(100 + k, 1000 * k), n, 0.06f,
      [k](std::size_t i) {
        return 0.2f + 0.11f * static_cast<float>(i) + 0.01f * static_cast<float>(k);
      },
      7);
  m.header.seq = static_cast<std::uint32_t>(k);
  m.ranges[1] = std::numeric_limits<float>::infinity();
  m.ranges[2] = std::numeric_limits<float>::quiet_NaN();
  m.ranges[3] = 0.0f;
  m.ranges[4] = 0.1f;
  m.ranges[5] = 12.5f;
  return m;
}

/// Equal floats, NaN equal to NaN.
inline bool sameFloat(float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

/// Everything of two LaserScans but their range values is equal (header, angles, limits,
/// intensities, number of ranges).
inline void expectSameScanButRanges(const sensor_msgs::LaserScan& x,
                                    const sensor_msgs::LaserScan& y) {
  EXPECT_EQ(x.header.stamp, y.header.stamp);
  EXPECT_EQ(x.header.seq, y.header.seq);
  EXPECT_EQ(x.header.frame_id, y.header.frame_id);
  EXPECT_EQ(x.angle_min, y.angle_min);
  EXPECT_EQ(x.angle_max, y.angle_max);
  EXPECT_EQ(x.angle_increment, y.angle_increment);
  EXPECT_EQ(x.time_increment, y.time_increment);
  EXPECT_EQ(x.scan_time, y.scan_time);
  EXPECT_EQ(x.range_min, y.range_min);
  EXPECT_EQ(x.range_max, y.range_max);
  EXPECT_EQ(x.intensities, y.intensities);
  EXPECT_EQ(x.ranges.size(), y.ranges.size());
}

}  // namespace lidarcal::test
