// SPDX-License-Identifier: BSD-3-Clause
#include "io/ros2_msgs.hpp"

#include <cstring>
#include <stdexcept>

#include "io/cdr.hpp"

namespace lidarcal::io {
namespace {

/// std_msgs/msg/Header: builtin_interfaces/msg/Time (int32 sec, uint32 nanosec), string frame_id.
void readHeader(CdrReader& in, std::int32_t& sec, std::uint32_t& nanosec, std::string& frame_id) {
  sec = in.i32();
  nanosec = in.u32();
  frame_id = in.str();
}

/// The header's stamp in seconds (sec + 1e-9 nanosec), its frame_id in `frame_id`.
double readHeader(CdrReader& in, std::string& frame_id) {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  readHeader(in, sec, nanosec, frame_id);
  return static_cast<double>(sec) + 1e-9 * static_cast<double>(nanosec);
}

/// geometry_msgs Point/Vector3 (3 float64) then Quaternion (x, y, z, w float64).
Transform3 readTransform(CdrReader& in) {
  const double x = in.f64(), y = in.f64(), z = in.f64();
  const double qx = in.f64(), qy = in.f64(), qz = in.f64(), qw = in.f64();
  return makeTransform({x, y, z}, Eigen::Quaterniond(qw, qx, qy, qz));
}

}  // namespace

LaserScanView Ros2LaserScan::view() const {
  LaserScanView v;
  v.stamp_sec = stamp_sec;
  v.stamp_nanosec = stamp_nanosec;
  v.angle_min = angle_min;
  v.angle_increment = angle_increment;
  v.range_min = range_min;
  v.range_max = range_max;
  v.ranges = ranges.data();
  v.count = ranges.size();
  v.intensities = intensities.data();
  v.intensity_count = intensities.size();
  return v;
}

void decodeLaserScan(const std::uint8_t* data, std::size_t size, Ros2LaserScan& msg) {
  CdrReader in(data, size);
  readHeader(in, msg.stamp_sec, msg.stamp_nanosec, msg.frame_id);
  msg.angle_min = in.f32();
  msg.angle_max = in.f32();
  msg.angle_increment = in.f32();
  msg.time_increment = in.f32();
  msg.scan_time = in.f32();
  msg.range_min = in.f32();
  msg.range_max = in.f32();
  in.f32Seq(msg.ranges);
  msg.ranges_offset = in.offset() - 4 * msg.ranges.size();
  msg.big_endian = in.bigEndian();
  in.f32Seq(msg.intensities);
}

void patchLaserScanRanges(const Ros2LaserScan& msg, std::uint8_t* data, std::size_t size) {
  if (msg.ranges_offset + 4 * msg.ranges.size() > size)
    throw std::logic_error(
        "patchLaserScanRanges: the message is not the one the scan was decoded from");
  std::uint8_t* p = data + msg.ranges_offset;
  for (float r : msg.ranges) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &r, sizeof bits);
    for (int b = 0; b < 4; ++b)
      *p++ = static_cast<std::uint8_t>(bits >> (8 * (msg.big_endian ? 3 - b : b)));
  }
}

Ros2StampedTransform decodeOdometry(const std::uint8_t* data, std::size_t size) {
  CdrReader in(data, size);
  Ros2StampedTransform o;
  o.stamp_s = readHeader(in, o.parent);
  o.child = in.str();
  o.transform = readTransform(in);  // pose.pose: position, orientation
  return o;
}

void decodeJointState(const std::uint8_t* data, std::size_t size, Ros2JointState& out) {
  CdrReader in(data, size);
  std::string frame_id;
  out.stamp_s = readHeader(in, frame_id);
  out.name.resize(in.count(5));  // a string: its 4-byte length and at least the NUL
  for (std::string& n : out.name) n = in.str();
  out.position.resize(in.count(8));
  for (double& p : out.position) p = in.f64();
}

std::vector<Ros2StampedTransform> decodeTfMessage(const std::uint8_t* data, std::size_t size) {
  CdrReader in(data, size);
  // A TransformStamped holds at least 4 + 4 + 4 + 4 bytes before its 56 bytes of float64.
  const std::uint32_t n = in.count(72);
  std::vector<Ros2StampedTransform> out(n);
  for (auto& t : out) {
    t.stamp_s = readHeader(in, t.parent);
    t.child = in.str();
    t.transform = readTransform(in);
  }
  return out;
}

}  // namespace lidarcal::io
