// SPDX-License-Identifier: BSD-3-Clause
// `lidarcal correct IN.bag --out OUT.bag`: every connection and message copied in order with the
// same stamps; only the LaserScan ranges of the topic change, to what `correct` gives for the
// imported sequence. Bags written here with the ROS libraries (the oracle), and the shared
// RPLIDAR recording when present.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include "io/pcd_scan.hpp"
#include "io/rig.hpp"
#include "io/rig_model_io.hpp"
#include "io/sequence.hpp"
#include "ros/laser_scan_util.hpp"
#include "ros_test_util.hpp"

namespace lidarcal::test {
namespace {

const std::string kSensor = "ROS1 sensor_msgs/LaserScan on /scan (frame laser)";

/// /scan: `scans` LaserScans of 100 beams; /chatter: strings from two publishers (two connections);
/// /scan_b: a second LaserScan topic when `second_topic`.
std::filesystem::path writeBag(const std::filesystem::path& file, int scans,
                               bool second_topic = false, std::size_t odd_beams_at = 0) {
  rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
  for (int k = 0; k < scans; ++k) {
    const sensor_msgs::LaserScan m =
        laserScan(k, k > 0 && static_cast<std::size_t>(k) == odd_beams_at ? 99 : 100);
    bag.write("/scan", m.header.stamp, m);
    std_msgs::String s;
    s.data = "message " + std::to_string(k);
    auto header = boost::make_shared<ros::M_string>();
    (*header)["callerid"] = k % 2 ? "/talker_a" : "/talker_b";
    (*header)["latching"] = "0";
    bag.write("/chatter", ros::Time(100 + k, 500), s, header);
    if (second_topic) bag.write("/scan_b", m.header.stamp + ros::Duration(0.001), m);
  }
  bag.close();
  return file;
}

struct BagMessage {
  std::string topic, datatype, callerid;
  ros::Time time;
  std::vector<std::uint8_t> bytes;
  sensor_msgs::LaserScan::ConstPtr scan;
};

std::vector<BagMessage> readAll(const std::filesystem::path& file,
                                std::size_t* connections = nullptr) {
  rosbag::Bag bag(file.string(), rosbag::bagmode::Read);
  rosbag::View view(bag);
  if (connections) *connections = view.getConnections().size();
  std::vector<BagMessage> out;
  for (const rosbag::MessageInstance& m : view) {
    BagMessage b{m.getTopic(), m.getDataType(), m.getCallerId(), m.getTime(), {}, nullptr};
    b.bytes.resize(m.size());
    ros::serialization::OStream s(b.bytes.data(), static_cast<std::uint32_t>(b.bytes.size()));
    m.write(s);
    if (m.getDataType() == "sensor_msgs/LaserScan")
      b.scan = m.instantiate<sensor_msgs::LaserScan>();
    out.push_back(std::move(b));
  }
  return out;
}

/// Everything but the ranges of `topic` is identical; returns the scans of the topic (in, out).
std::vector<std::pair<sensor_msgs::LaserScan::ConstPtr, sensor_msgs::LaserScan::ConstPtr>>
expectSameBagButRanges(const std::filesystem::path& in, const std::filesystem::path& out,
                       const std::string& topic) {
  std::size_t cin = 0, cout = 0;
  const auto a = readAll(in, &cin);
  const auto b = readAll(out, &cout);
  EXPECT_EQ(cin, cout);
  EXPECT_EQ(a.size(), b.size());
  std::vector<std::pair<sensor_msgs::LaserScan::ConstPtr, sensor_msgs::LaserScan::ConstPtr>> scans;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(a[i].topic, b[i].topic);
    EXPECT_EQ(a[i].datatype, b[i].datatype);
    EXPECT_EQ(a[i].callerid, b[i].callerid);
    EXPECT_EQ(a[i].time, b[i].time);
    if (a[i].topic != topic) {
      EXPECT_EQ(a[i].bytes, b[i].bytes);
      continue;
    }
    expectSameScanButRanges(*a[i].scan, *b[i].scan);
    scans.emplace_back(a[i].scan, b[i].scan);
  }
  return scans;
}

/// Readings the importer turns into points are corrected (f(out) = in inside the fitted readings,
/// f continued as its tangent at the nearer edge beyond them); the others are left bit for bit.
void expectRangesCorrected(const sensor_msgs::LaserScan& in, const sensor_msgs::LaserScan& out,
                           const CalibrationModel& m) {
  const auto& f = m.model.bias;
  const double lo = f(m.fitted_range_m->first), hi = f(m.fitted_range_m->second);
  std::size_t corrected = 0;
  for (std::size_t i = 0; i < in.ranges.size(); ++i) {
    SCOPED_TRACE(i);
    const float r = in.ranges[i];
    const bool reading = std::isfinite(r) && r > 0.0f && r >= in.range_min && r <= in.range_max;
    if (!reading) {
      EXPECT_TRUE(sameFloat(r, out.ranges[i])) << r << " -> " << out.ranges[i];
      continue;
    }
    if (r < lo || r > hi) {
      const double edge = r < lo ? m.fitted_range_m->first : m.fitted_range_m->second;
      EXPECT_NEAR(out.ranges[i], edge + (r - f(edge)) / f.derivative(edge), 2e-6);
      continue;
    }
    EXPECT_NEAR(m.model.bias(out.ranges[i]), r, 2e-6);  // float output
    ++corrected;
  }
  EXPECT_GT(corrected, in.ranges.size() / 2);
}

TEST(CorrectBag, CopiesEveryMessageAndCorrectsTheRanges) {
  TempDir dir;
  const auto in = writeBag(dir / "in.bag", 20);
  const CalibrationModel m = polynomialModel(kSensor, 100);
  io::writeModel(dir / "model.json", m);
  const CliResult r = runCli("correct " + in.string() + " --model " +
                             (dir / "model.json").string() + " -o " + (dir / "out.bag").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto scans = expectSameBagButRanges(in, dir / "out.bag", "/scan");
  ASSERT_EQ(scans.size(), 20u);
  for (const auto& [a, b] : scans) expectRangesCorrected(*a, *b, m);
  // Atomic: no temporary file left beside the output.
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    files += e.is_regular_file();
  EXPECT_EQ(files, 3u);  // in.bag, model.json, out.bag
}

TEST(CorrectBag, RangesEqualCorrectOnTheImportedSequence) {
  TempDir dir;
  const auto in = writeBag(dir / "in.bag", 5);
  io::writeModel(dir / "model.json", polynomialModel(kSensor, 100));
  const std::string model = " --model " + (dir / "model.json").string();
  for (const std::string options :
       {" --inversion ml", " --outside drop", " --outside extrapolate"}) {
    SCOPED_TRACE(options);
    std::filesystem::remove_all(dir / "seq");
    std::filesystem::remove_all(dir / "seq-out");
    std::filesystem::remove(dir / "out.bag");
    ASSERT_EQ(runCli("import " + in.string() + " -o " + (dir / "seq").string()).exit_code, 0);
    const CliResult s = runCli("correct " + (dir / "seq").string() + model + options + " -o " +
                               (dir / "seq-out").string());
    ASSERT_EQ(s.exit_code, 0) << s.err;
    const CliResult b =
        runCli("correct " + in.string() + model + options + " -o " + (dir / "out.bag").string());
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const io::Sequence seq = io::openSequence(dir / "seq-out");
    const auto bag = readAll(dir / "out.bag");
    std::size_t k = 0, compared = 0;
    for (const auto& msg : bag) {
      if (msg.topic != "/scan") continue;
      ASSERT_LT(k, seq.scans.size());
      const io::Scan scan = io::readScan(seq.scans[k++].path);
      ASSERT_EQ(scan.cloud->size(), msg.scan->ranges.size());
      for (std::size_t i = 0; i < scan.cloud->size(); ++i) {
        const auto& p = (*scan.cloud)[i];
        const float r = msg.scan->ranges[i];
        const bool reading =
            std::isfinite(r) && r >= msg.scan->range_min && r <= msg.scan->range_max;
        if (std::isnan(p.x)) {
          EXPECT_TRUE(!reading || std::isnan(r)) << i << ": " << r;  // no return in both
          continue;
        }
        ++compared;
        // The sequence's point went through float x, y: the reading correct saw differs from the
        // bag's by float rounding, hence the tolerance.
        EXPECT_NEAR(std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)), r, 1e-5) << i;
      }
    }
    EXPECT_EQ(k, seq.scans.size());
    EXPECT_GT(compared, 5u * 50u);
  }
}

TEST(CorrectBag, TopicChoice) {
  TempDir dir;
  const auto in = writeBag(dir / "in.bag", 4, true);
  io::writeModel(dir / "model.json", polynomialModel("", 100));
  const std::string model = " --model " + (dir / "model.json").string();
  const CliResult several =
      runCli("correct " + in.string() + model + " -o " + (dir / "out.bag").string());
  EXPECT_EQ(several.exit_code, 2);
  EXPECT_NE(several.err.find("several LaserScan topics"), std::string::npos) << several.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.bag"));
  const CliResult b = runCli("correct " + in.string() + model + " --topic /scan_b -o " +
                             (dir / "out.bag").string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const auto scans = expectSameBagButRanges(in, dir / "out.bag", "/scan_b");
  ASSERT_EQ(scans.size(), 4u);
  for (const auto& [x, y] : scans) expectRangesCorrected(*x, *y, polynomialModel("", 100));
}

TEST(CorrectBag, RigModelCorrectsEachTopicWithItsOwnBlock) {
  TempDir dir;
  const auto in = writeBag(dir / "in.bag", 6, true);
  const io::RigModel rig = twoLidarModel("/scan", "/scan_b");
  io::writeRigModel(dir / "rig.json", rig);
  const std::string model = " --model " + (dir / "rig.json").string();
  const CliResult r =
      runCli("correct " + in.string() + model + " -o " + (dir / "out.bag").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto a = readAll(in), b = readAll(dir / "out.bag");
  ASSERT_EQ(a.size(), b.size());
  std::size_t front = 0, back = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    SCOPED_TRACE(i);
    ASSERT_EQ(a[i].topic, b[i].topic);
    if (a[i].topic == "/scan")
      expectRangesCorrected(*a[i].scan, *b[i].scan, rig.sensors[0].model), ++front;
    else if (a[i].topic == "/scan_b")
      expectRangesCorrected(*a[i].scan, *b[i].scan, rig.sensors[1].model), ++back;
    else
      EXPECT_EQ(a[i].bytes, b[i].bytes);
  }
  EXPECT_EQ(front, 6u);
  EXPECT_EQ(back, 6u);
  // One block by name: the other topic is copied as it was.
  const CliResult one =
      runCli("correct " + in.string() + model + " --sensor back -o " + (dir / "back.bag").string());
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const auto scans = expectSameBagButRanges(in, dir / "back.bag", "/scan_b");
  ASSERT_EQ(scans.size(), 6u);
  for (const auto& [x, y] : scans) expectRangesCorrected(*x, *y, rig.sensors[1].model);
  // A sequence needs the block named; the error lists the blocks.
  ASSERT_EQ(
      runCli("import " + in.string() + " --topic /scan -o " + (dir / "seq").string()).exit_code, 0);
  const CliResult seq =
      runCli("correct " + (dir / "seq").string() + model + " -o " + (dir / "seq-out").string());
  EXPECT_EQ(seq.exit_code, 2);
  EXPECT_NE(seq.err.find("front (/scan)"), std::string::npos) << seq.err;
  const CliResult unknown =
      runCli("correct " + in.string() + model + " --sensor side -o " + (dir / "x.bag").string());
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("'side'"), std::string::npos) << unknown.err;
}

TEST(ImportRig, TwoTopicsKeepEachScansSensor) {
  TempDir dir;
  const auto in = writeBag(dir / "in.bag", 5, true);
  const CliResult r =
      runCli("import " + in.string() + " --topic /scan,/scan_b --sensor-names front,back -o " +
             (dir / "rig").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const io::Rig rig = io::openRig(dir / "rig");
  ASSERT_EQ(rig.meta.sensors.size(), 2u);
  EXPECT_EQ(rig.meta.sensors[1].name, "back");
  EXPECT_EQ(rig.meta.sensors[1].topic, "/scan_b");
  ASSERT_EQ(rig.scans.size(), 10u);
  std::size_t back = 0;
  for (const io::RigScan& s : rig.scans) back += s.sensor == "back";
  EXPECT_EQ(back, 5u);
  for (const io::Sequence& seq : rig.sequences) EXPECT_EQ(seq.scans.size(), 5u);
  // Single-topic imports are unchanged: no rig files.
  ASSERT_EQ(
      runCli("import " + in.string() + " --topic /scan -o " + (dir / "one").string()).exit_code, 0);
  EXPECT_FALSE(io::isRigDirectory(dir / "one"));
  const CliResult names =
      runCli("import " + in.string() + " --topic /scan,/scan_b --sensor-names a -o " +
             (dir / "x").string());
  EXPECT_EQ(names.exit_code, 2);
  EXPECT_NE(names.err.find("--sensor-names"), std::string::npos) << names.err;
}

TEST(CorrectBag, RefusesAnotherSensorsModelAndLeavesNoOutput) {
  TempDir dir;
  const auto in = writeBag(dir / "in.bag", 6, false, 4);  // message 4 has 99 beams
  const std::string out = " -o " + (dir / "out.bag").string();
  io::writeModel(dir / "other.json", polynomialModel("RPLIDAR A2", 100));
  const CliResult name =
      runCli("correct " + in.string() + " --model " + (dir / "other.json").string() + out);
  EXPECT_EQ(name.exit_code, 2);
  EXPECT_NE(name.err.find("sensor_name"), std::string::npos) << name.err;
  io::writeModel(dir / "beams.json", polynomialModel(kSensor, 100));
  const CliResult beams =
      runCli("correct " + in.string() + " --model " + (dir / "beams.json").string() + out);
  EXPECT_EQ(beams.exit_code, 2);
  EXPECT_NE(beams.err.find("99 beams"), std::string::npos) << beams.err;
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    files += e.is_regular_file();
  EXPECT_EQ(files, 3u) << "an output or a temporary file was left";  // in.bag and the two models
  writeFile(dir / "out.bag", "keep");
  io::writeModel(dir / "any.json", polynomialModel("", 0));
  const CliResult taken =
      runCli("correct " + in.string() + " --model " + (dir / "any.json").string() + out);
  EXPECT_EQ(taken.exit_code, 2);
  EXPECT_EQ(readFile(dir / "out.bag"), "keep");
  const CliResult ascii = runCli("correct " + in.string() + " --ascii --overwrite --model " +
                                 (dir / "any.json").string() + out);
  EXPECT_EQ(ascii.exit_code, 2);
}

TEST(CorrectBag, SharedRplidarRecording) {
  const auto in = sharedData() / "rplidar_a2_room" / "rplidar_1.bag";
  if (!std::filesystem::exists(in)) GTEST_SKIP() << "shared recording absent: " << in;
  TempDir dir;
  // A model for this sensor (name and limits as import writes them), beams from the bag itself.
  ASSERT_EQ(
      runCli("import " + in.string() + " --max-scans 1 -o " + (dir / "seq").string()).exit_code, 0);
  const io::Sequence seq = io::openSequence(dir / "seq");
  CalibrationModel m = polynomialModel(seq.meta.sensor_name.value_or(""),
                                       static_cast<int>(seq.scans.front().points));
  m.model.range_min_m = seq.meta.range_min_m.value_or(0.0);
  m.model.range_max_m = seq.meta.range_max_m.value_or(12.0);
  io::writeModel(dir / "model.json", m);
  const CliResult r = runCli("correct " + in.string() + " --model " +
                             (dir / "model.json").string() + " -o " + (dir / "out.bag").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto scans = expectSameBagButRanges(in, dir / "out.bag", "/scan_rplidar");
  EXPECT_EQ(scans.size(), 1319u);
  for (std::size_t i = 0; i < scans.size(); i += 97)
    expectRangesCorrected(*scans[i].first, *scans[i].second, m);
}

// --- import --pose odom:TOPIC | tf:FRAME --------------------------------------------------

/// The robot's base in odom: still at (0, 0, 0) until 2 s, drives to (1, 0.5, 0.3) by 4 s
/// (linear in position and heading), still after.
Pose2 baseAt(double t) {
  const double u = std::clamp((t - 2.0) / 2.0, 0.0, 1.0);
  return {1.0 * u, 0.5 * u, 0.3 * u};
}
constexpr double kT0 = 1000.0;       // bag time of t = 0
const Pose2 kMount{0.2, -0.1, 0.5};  // laser on base_link (/tf_static)

geometry_msgs::Quaternion yawQuaternion(double yaw) {
  geometry_msgs::Quaternion q;
  q.w = std::cos(yaw / 2);
  q.z = std::sin(yaw / 2);
  return q;
}

geometry_msgs::TransformStamped stamped(const std::string& parent, const std::string& child,
                                        double t, const Pose2& p) {
  geometry_msgs::TransformStamped s;
  s.header.frame_id = parent;
  s.header.stamp = ros::Time(kT0 + t);
  s.child_frame_id = child;
  s.transform.translation.x = p.x_m;
  s.transform.translation.y = p.y_m;
  s.transform.rotation = yawQuaternion(p.yaw_rad);
  return s;
}

/// Scans at 10 Hz from 0.05 s to 5.95 s; odometry at 7 Hz over 0-6 s; /tf: map -> odom fixed at
/// (1, 2, 0.5) at 5 Hz and odom -> base_link at 7 Hz; /tf_static: base_link -> laser.
std::filesystem::path writePoseBag(const std::filesystem::path& file) {
  rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
  tf2_msgs::TFMessage mount;
  mount.transforms.push_back(stamped("base_link", "laser", 0.0, kMount));
  bag.write("/tf_static", ros::Time(kT0), mount);
  for (int i = 0; i <= 42; ++i) {
    const double t = i / 7.0;
    nav_msgs::Odometry o;
    o.header.stamp = ros::Time(kT0 + t);
    o.header.frame_id = "odom";
    o.child_frame_id = "base_link";
    const Pose2 b = baseAt(t);
    o.pose.pose.position.x = b.x_m;
    o.pose.pose.position.y = b.y_m;
    o.pose.pose.orientation = yawQuaternion(b.yaw_rad);
    bag.write("/odom", o.header.stamp, o);
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(stamped("odom", "base_link", t, b));
    if (i % 2 == 0) tf.transforms.push_back(stamped("map", "odom", t, {1.0, 2.0, 0.5}));
    bag.write("/tf", o.header.stamp, tf);
  }
  for (int k = 0; k < 60; ++k) {
    sensor_msgs::LaserScan m = laserScan(k, 100);
    m.header.stamp = ros::Time(kT0 + 0.05 + 0.1 * k);
    bag.write("/scan", m.header.stamp, m);
  }
  bag.close();
  return file;
}

/// The laser's pose at time t in `world` (odom, or map = (1, 2, 0.5) * odom).
Pose2 laserAt(double t, bool in_map) {
  const Pose2 b = baseAt(t);
  Pose2 p;
  b.toWorld(kMount.x_m, kMount.y_m, p.x_m, p.y_m);
  p.yaw_rad = b.yaw_rad + kMount.yaw_rad;
  if (!in_map) return p;
  const Pose2 map_odom{1.0, 2.0, 0.5};
  Pose2 q;
  map_odom.toWorld(p.x_m, p.y_m, q.x_m, q.y_m);
  q.yaw_rad = p.yaw_rad + map_odom.yaw_rad;
  return q;
}

class ImportPose : public ::testing::TestWithParam<const char*> {};

// Each scan's VIEWPOINT is the laser's pose at its stamp (the closed form above: the base moves
// linearly in position and heading, so interpolating it between samples is exact, and the mount
// is composed after), and each still phase is one stop.
TEST_P(ImportPose, ViewpointIsTheLasersPoseAtEachStamp) {
  const std::string pose = GetParam();
  const bool in_map = pose == "tf:map";
  TempDir dir;
  const auto in = writePoseBag(dir / "pose.bag");
  const CliResult r = runCli("import " + in.string() + " --topic /scan --pose " + pose + " -o " +
                             (dir / "seq").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("stops"), std::string::npos) << r.out;
  const io::Sequence seq = io::openSequence(dir / "seq");
  ASSERT_EQ(seq.scans.size(), 60u);
  std::size_t still = 0;
  for (std::size_t k = 0; k < seq.scans.size(); ++k) {
    SCOPED_TRACE(k);
    const double t = 0.05 + 0.1 * static_cast<double>(k);
    const Pose2 v = seq.scans[k].viewpoint;
    // Still phases: the stop's first pose (itself the true pose there).
    const bool moving = t > 2.0 && t < 4.0;
    const Pose2 truth = laserAt(t, in_map);
    const double tol = 5e-5;  // VIEWPOINT: float, written with 6 significant digits
    EXPECT_NEAR(v.x_m, truth.x_m, tol);
    EXPECT_NEAR(v.y_m, truth.y_m, tol);
    EXPECT_NEAR(wrapAngle(v.yaw_rad - truth.yaw_rad), 0.0, tol);
    still += !moving;
  }
  // Stops: all scans of 0-2 s share one VIEWPOINT, all of 4-6 s another; moving scans (0.15 rad/s
  // and 0.56 m/s, 5.6 cm per scan) each their own.
  EXPECT_EQ(seq.stops.size(), 2u + (seq.scans.size() - still));
  EXPECT_EQ(seq.stops.front().scans.size(), 20u);
  EXPECT_EQ(seq.stops.back().scans.size(), 20u);
}

INSTANTIATE_TEST_SUITE_P(Sources, ImportPose, ::testing::Values("odom:/odom", "tf:map", "tf:odom"),
                         [](const auto& p) {
                           std::string name;
                           for (const char c : std::string(p.param))
                             name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return name;
                         });

TEST(ImportPoseErrors, NamesTheSourceAndWhatToDo) {
  TempDir dir;
  const auto in = writePoseBag(dir / "pose.bag");
  const std::string base = "import " + in.string() + " --topic /scan -o " + (dir / "seq").string();
  const CliResult wrong_type = runCli(base + " --pose odom:/scan");
  EXPECT_EQ(wrong_type.exit_code, 2);
  EXPECT_NE(wrong_type.err.find("nav_msgs/Odometry"), std::string::npos) << wrong_type.err;
  const CliResult no_frame = runCli(base + " --pose tf:world");
  EXPECT_EQ(no_frame.exit_code, 3);
  EXPECT_NE(no_frame.err.find("not connected to 'world'"), std::string::npos) << no_frame.err;
  EXPECT_EQ(runCli(base + " --pose odometry").exit_code, 2);
  EXPECT_EQ(runCli(base + " --pose tf:").exit_code, 2);
  EXPECT_EQ(runCli(base + " --still-m 0.1").exit_code, 2);  // without --pose
  EXPECT_FALSE(std::filesystem::exists(dir / "seq"));
  // A looser tolerance: the whole drive (1.1 m, 17 deg) stays within 2 m and 30 deg of the first
  // pose: one stop.
  const CliResult loose = runCli(base + " --pose odom:/odom --still-m 2 --still-deg 30");
  ASSERT_EQ(loose.exit_code, 0) << loose.err;
  EXPECT_EQ(io::openSequence(dir / "seq").stops.size(), 1u);
}

TEST(ImportPose, SharedAgvBagsStandStill) {
  const auto dir_in = sharedData() / "hokuyo_ust30lx_reflector" / "agv_two_lidars";
  if (!std::filesystem::exists(dir_in / "obs2.bag"))
    GTEST_SKIP() << "shared recordings absent: " << dir_in;
  TempDir dir;
  std::vector<Pose2> first;
  for (const std::string topic : {"/scan_front", "/scan_back"}) {
    SCOPED_TRACE(topic);
    const auto out = dir / topic.substr(1);
    // The vehicle's localisation (map -> base_footprint) jitters by a few centimetres while it
    // stands: the default 1 cm splits the recording into many stops and says what to try.
    const std::string import = "import " + (dir_in / "obs2.bag").string() + " --topic " + topic +
                               " --pose tf:map -o " + out.string() + " --overwrite";
    const CliResult tight = runCli(import);
    ASSERT_EQ(tight.exit_code, 0) << tight.err;
    EXPECT_NE(tight.out.find("try --still-m 0.05"), std::string::npos) << tight.out;
    const CliResult r = runCli(import + " --still-m 0.05 --still-deg 1");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("upside down"), std::string::npos) << r.out;
    const io::Sequence seq = io::openSequence(out);
    ASSERT_GT(seq.scans.size(), 50u);
    EXPECT_EQ(seq.stops.size(), 1u);  // the forklift stands still
    first.push_back(seq.scans.front().viewpoint);
  }
  // The two lidars sit at opposite ends of the vehicle: different positions, headings about
  // opposite.
  EXPECT_GT(std::hypot(first[0].x_m - first[1].x_m, first[0].y_m - first[1].y_m), 0.5);
}

}  // namespace
}  // namespace lidarcal::test
