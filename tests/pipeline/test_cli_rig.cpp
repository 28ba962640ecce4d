// SPDX-License-Identifier: BSD-3-Clause
// A simulated two-lidar vehicle through the command line: its scans written as a two-topic ROS1
// bag with the designed mountings in /tf_static, `import --topic a,b`, `calibrate RIG`, and the
// rig model read back against the simulated truth (the same vehicle as the coverage bench's
// static scenario, tests/calibration/rig_scenes.hpp).

#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include <rosbag/bag.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>
#include <Eigen/Dense>

#include "calibration/rig_scenes.hpp"
#include "io/rig_model_io.hpp"
#include "test_util.hpp"

namespace lidarcal::test {
namespace {

constexpr double kT0 = 1000.0;  // bag time of the first scan

std::string topicOf(const simulation::RigSimSensor& s) { return "/scan_" + s.name; }
std::string frameOf(const simulation::RigSimSensor& s) { return "laser_" + s.name; }

/// base_link -> the sensor's frame as /tf_static holds a mounting: yaw about z, then a roll of
/// pi about x when upside down (so the scan's x axis keeps the mounting's heading).
geometry_msgs::TransformStamped mountingTransform(const simulation::RigSimSensor& s) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = "base_link";
  t.header.stamp = ros::Time(kT0);
  t.child_frame_id = frameOf(s);
  t.transform.translation.x = s.design.x_m;
  t.transform.translation.y = s.design.y_m;
  t.transform.translation.z = s.design.z_m;
  const double c = std::cos(s.design.yaw_rad / 2), n = std::sin(s.design.yaw_rad / 2);
  // q_z(yaw) q_x(pi)
  if (s.mounting.upside_down)
    t.transform.rotation.x = c, t.transform.rotation.y = n;
  else
    t.transform.rotation.w = c, t.transform.rotation.z = n;
  return t;
}

/// /tf for a vehicle that stands still at the origin of `map` while its localisation jitters by
/// 2 cm from one pose to the next, every 0.1 s (the scans' period) from just before `from_s` to
/// just after `to_s`.
void writeJitteringPoses(rosbag::Bag& bag, double from_s, double to_s) {
  for (int k = 0; from_s - 0.1 + 0.1 * k <= to_s + 0.1; ++k) {
    geometry_msgs::TransformStamped t;
    t.header.frame_id = "map";
    t.header.stamp = ros::Time(from_s - 0.1 + 0.1 * k);
    t.child_frame_id = "base_link";
    t.transform.translation.x = k % 2 == 0 ? 0.0 : 0.02;
    t.transform.rotation.w = 1.0;
    tf2_msgs::TFMessage m;
    m.transforms.push_back(t);
    bag.write("/tf", t.header.stamp, m);
  }
}

/// The simulated sightings as LaserScans: one per sensor and scan, no return (inf) off the poles.
/// With `jittering_poses`, /tf holds a still vehicle's jittering poses in `map`.
void writeRigBag(const std::filesystem::path& file, const simulation::RigSimConfig& sim,
                 const RigObservations& obs, bool jittering_poses = false) {
  // by the simulator's scan index (unique over sensors)
  std::map<std::size_t, sensor_msgs::LaserScan> scans;
  const std::size_t S = sim.sensors.size();
  for (const RigSighting& g : obs.sightings) {
    const simulation::RigSimSensor& s = sim.sensors[g.sensor];
    auto [it, fresh] = scans.try_emplace(g.scan);
    sensor_msgs::LaserScan& m = it->second;
    if (fresh) {
      m.header.frame_id = frameOf(s);
      m.header.stamp = ros::Time(kT0 + 0.1 * static_cast<double>(g.scan / S) +
                                 0.01 * static_cast<double>(g.sensor));
      m.angle_min = static_cast<float>(s.angle_min_rad);
      m.angle_increment = static_cast<float>(s.angle_increment_rad);
      m.angle_max = static_cast<float>(s.angle_min_rad + s.angle_increment_rad * (s.beams - 1));
      m.range_min = static_cast<float>(s.model.range_min_m);
      m.range_max = static_cast<float>(s.model.range_max_m);
      m.ranges.assign(static_cast<std::size_t>(s.beams), std::numeric_limits<float>::infinity());
    }
    for (const BeamReading& b : g.beams) m.ranges[b.beam] = static_cast<float>(b.range_m);
  }
  rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
  tf2_msgs::TFMessage mounts;
  for (const auto& s : sim.sensors) mounts.transforms.push_back(mountingTransform(s));
  bag.write("/tf_static", ros::Time(kT0), mounts);
  if (jittering_poses && !scans.empty())
    writeJitteringPoses(bag, kT0, scans.rbegin()->second.header.stamp.toSec());
  for (const auto& [index, m] : scans)
    bag.write(topicOf(sim.sensors[index % S]), m.header.stamp, m);
}

double standardError(const std::array<double, 9>& c, int i) {
  return std::sqrt(c[static_cast<std::size_t>(4 * i)]);
}

TEST(CalibrateRig, TwoLidarBagGivesTheTrueRelativeMountingAndBiases) {
  TempDir dir;
  const simulation::RigSimConfig sim = staticVehicle(false);
  const simulation::RigSimSample sample = simulation::simulateRig(sim, 7);
  writeRigBag(dir / "rig.bag", sim, sample.obs);
  const CliResult imported = runCli(
      "import " + (dir / "rig.bag").string() +
      " --topic /scan_front,/scan_back --sensor-names front,back -o " + (dir / "rig").string());
  ASSERT_EQ(imported.exit_code, 0) << imported.err;
  const CliResult calibrated = runCli("calibrate " + (dir / "rig").string() +
                                      " --radius 0.045 -o " + (dir / "model.json").string());
  ASSERT_EQ(calibrated.exit_code, 0) << calibrated.out << calibrated.err;
  const io::RigModel model = io::readRigModel(dir / "model.json");
  ASSERT_EQ(model.sensors.size(), 2u);
  ASSERT_EQ(model.relative.size(), 1u);
  EXPECT_EQ(model.frame, "relative");  // a vehicle that does not move: relative mountings only
  ASSERT_TRUE(model.scale_free);       // and its range scale relative to the front lidar's

  // The geometry comes in the front lidar's range units: true lengths times its alpha_1.
  const double scale = sim.sensors[0].model.bias.alpha[1];
  const io::RigModelRelative& rel = model.relative[0];
  EXPECT_EQ(rel.reference, "front");
  EXPECT_EQ(rel.sensor, "back");
  const Pose2 truth = relativeMounting(sim.sensors[0].mounting, sim.sensors[1].mounting);
  EXPECT_NEAR(rel.pose.x_m, scale * truth.x_m, 3.0 * standardError(rel.covariance, 0));
  EXPECT_NEAR(rel.pose.y_m, scale * truth.y_m, 3.0 * standardError(rel.covariance, 1));
  EXPECT_NEAR(wrapAngle(rel.pose.yaw_rad - truth.yaw_rad), 0.0,
              3.0 * standardError(rel.covariance, 2));
  // Not a tautology: the designs in /tf_static are centimetres and degrees off.
  const Pose2 design = relativeMounting(sim.sensors[0].design, sim.sensors[1].design);
  EXPECT_GT(std::hypot(design.x_m - truth.x_m, design.y_m - truth.y_m),
            6.0 * standardError(rel.covariance, 0));

  // Each sensor's reading at a true distance d: f_s(d) against the fitted f at d in those units.
  for (std::size_t s = 0; s < 2; ++s) {
    const CalibrationModel& m = model.sensors[s].model;
    SCOPED_TRACE(model.sensors[s].name);
    ASSERT_TRUE(m.fitted_range_m);
    const auto n = static_cast<Eigen::Index>(m.model.bias.alpha.size());
    ASSERT_EQ(m.alpha_covariance.size(), static_cast<std::size_t>(n * n));
    const Eigen::MatrixXd cov =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            m.alpha_covariance.data(), n, n);
    for (const double u : {0.1, 0.5, 0.9}) {
      const double d =
          (m.fitted_range_m->first + u * (m.fitted_range_m->second - m.fitted_range_m->first)) /
          scale;
      Eigen::VectorXd g(n);
      for (Eigen::Index k = 0; k < n; ++k) g(k) = std::pow(scale * d, static_cast<double>(k));
      const double fitted = m.model.bias(scale * d), true_reading = sim.sensors[s].model.bias(d);
      // Held alpha_1 of the front: its SE counts the offset only; 0.1 mm floors a zero variance.
      const double se = std::max(std::sqrt(g.dot(cov * g)), 1e-4);
      EXPECT_NEAR(fitted, true_reading, 3.0 * se) << "d " << d << " m";
    }
  }
}

// A vehicle that stood still while its poses jittered: every scan makes a stop of its own. Import
// says so once, on stderr, naming each sensor and recording, instead of a line of stops per topic
// and recording among the notes.
TEST(ImportRig, StopsSplitByJitterGiveOneLabelledWarning) {
  TempDir dir;
  const simulation::RigSimConfig sim = staticVehicle(false);
  const simulation::RigSimSample sample = simulation::simulateRig(sim, 7);
  writeRigBag(dir / "rig.bag", sim, sample.obs, true);
  const CliResult r =
      runCli("import " + (dir / "rig.bag").string() +
             " --topic /scan_front,/scan_back --sensor-names front,back --pose tf:map -o " +
             (dir / "rig").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("lidarcal: warning: front in rig.bag, back in rig.bag: most stops hold one "
                       "or two scans"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("try --still-m 0.05 --still-deg 1"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("most stops hold"), std::string::npos) << r.out;
  std::istringstream lines(r.out);
  std::string line;
  while (std::getline(lines, line)) {
    // No unlabelled "N stops (...)" line: the vehicle's stops are on the labelled line alone.
    const auto words = line.find_first_not_of(' ');
    if (words != std::string::npos && std::isdigit(static_cast<unsigned char>(line[words]))) {
      EXPECT_EQ(line.find(" stops ("), std::string::npos) << line;
    }
  }
  EXPECT_NE(r.out.find("vehicle poses: tf:map; "), std::string::npos) << r.out;
}

}  // namespace
}  // namespace lidarcal::test
