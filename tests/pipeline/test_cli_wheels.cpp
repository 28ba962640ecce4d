// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal import BAG --wheels TOPIC:LEFT,RIGHT` on a ROS 2 bag: each wheel's angle at each
// scan's stamp in SEQ/wheel_angles.csv, interpolated between the joint states around it; scans
// outside the joint states get no row; wrong joints or topics are named.

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "io/rosbag2_test_writer.hpp"
#include "io/wheel_angles_csv.hpp"
#include "test_util.hpp"

namespace lidarcal::test {
namespace {

constexpr int kScans = 12;

/// A sensor_msgs/msg/JointState in CDR: stamp, joint names, positions (no velocity or effort).
std::string jointStateCdr(double stamp_s, const std::vector<std::string>& names,
                          const std::vector<double>& positions) {
  CdrWriter w(false);
  const double sec = std::floor(stamp_s);
  w.i32(static_cast<std::int32_t>(sec));
  w.u32(static_cast<std::uint32_t>(std::lround((stamp_s - sec) * 1e9)));
  w.str("base_link");
  w.u32(static_cast<std::uint32_t>(names.size()));
  for (const std::string& n : names) w.str(n);
  w.u32(static_cast<std::uint32_t>(positions.size()));
  for (double p : positions) w.f64(p);
  w.u32(0);  // velocity
  w.u32(0);  // effort
  return w.bytes();
}

/// The wheels' true angles at time t: what the test expects at each scan.
double leftAt(double t) { return 2.0 * (t - 100.0); }
double rightAt(double t) { return -1.0 + 3.0 * (t - 100.0); }

/// Scans at 100 + k s (+ k us), joint states every 0.3 s from 100.5 s to 108.3 s, with a message
/// of another controller's joints between them.
std::filesystem::path writeBag(const std::filesystem::path& file) {
  std::string out = mcapHead() + schemaRecord(1, "sensor_msgs/msg/LaserScan") +
                    schemaRecord(2, "sensor_msgs/msg/JointState") + channelRecord(1, 1, "/scan") +
                    channelRecord(2, 2, "/joint_states");
  std::string chunk;
  for (int k = 0; k < kScans; ++k) {
    const TestScan s = recordedScan(k, 50);
    chunk += messageRecord(1, 1000000000ull * static_cast<std::uint64_t>(s.sec) + s.nanosec,
                           laserScanCdr(s));
  }
  for (double t = 100.5; t < 108.35; t += 0.3) {
    const auto ns = static_cast<std::uint64_t>(std::llround(t * 1e9));
    chunk += messageRecord(
        2, ns, jointStateCdr(t, {"caster", "wheel_r", "wheel_l"}, {0.5, rightAt(t), leftAt(t)}));
    chunk += messageRecord(2, ns + 1, jointStateCdr(t, {"arm_joint"}, {1.0}));
  }
  writeFile(file, out + chunkRecord(chunk, "", 0, 0) + mcapTail());
  return file;
}

TEST(CliWheels, EachScansWheelAnglesAreInterpolatedAtItsStamp) {
  TempDir dir;
  const auto bag = writeBag(dir / "drive.mcap");
  const auto r = runCli("import " + bag.string() + " -o " + (dir / "seq").string() +
                        " --wheels /joint_states:wheel_l,wheel_r");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("wheel angles: 8 of 12 scans"), std::string::npos) << r.out;
  const auto rows = io::readWheelAnglesCsv(dir / "seq" / "wheel_angles.csv");
  // scans 1..8 (101..108 s) lie inside the joint states (100.5..108.3 s); 0 and 9..11 do not
  ASSERT_EQ(rows.size(), 8u);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const int k = static_cast<int>(i) + 1;
    const TestScan s = recordedScan(k, 50);
    const double t = s.sec + 1e-9 * s.nanosec;
    EXPECT_EQ(rows[i].file, "scan_" + std::string(5, '0') + std::to_string(k) + ".pcd");
    EXPECT_NEAR(rows[i].left_rad, leftAt(t), 1e-6) << k;
    EXPECT_NEAR(rows[i].right_rad, rightAt(t), 1e-6) << k;
  }
}

TEST(CliWheels, JointsTheBagDoesNotHaveAreNamedWithThoseItHas) {
  TempDir dir;
  const auto bag = writeBag(dir / "drive.mcap");
  const auto r = runCli("import " + bag.string() + " -o " + (dir / "seq").string() +
                        " --wheels /joint_states:left_wheel_joint,right_wheel_joint");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("left_wheel_joint"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("wheel_l"), std::string::npos) << "the joints seen are listed: " << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "seq"));
}

TEST(CliWheels, ATopicThatIsNotJointStateOrAMalformedOptionIsRefused) {
  TempDir dir;
  const auto bag = writeBag(dir / "drive.mcap");
  const auto wrong_topic = runCli("import " + bag.string() + " -o " + (dir / "seq").string() +
                                  " --wheels /scan:wheel_l,wheel_r");
  EXPECT_EQ(wrong_topic.exit_code, 2);
  EXPECT_NE(wrong_topic.err.find("sensor_msgs/msg/JointState"), std::string::npos)
      << wrong_topic.err;
  const auto malformed = runCli("import " + bag.string() + " -o " + (dir / "seq").string() +
                                " --wheels /joint_states");
  EXPECT_EQ(malformed.exit_code, 2);
  EXPECT_NE(malformed.err.find("TOPIC:LEFT_JOINT,RIGHT_JOINT"), std::string::npos) << malformed.err;
}

}  // namespace
}  // namespace lidarcal::test
