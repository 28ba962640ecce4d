// SPDX-License-Identifier: BSD-3-Clause
// observations.csv, odometry.csv, observation scenes, noise settings and the landmarks.csv
// converter.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/landmarks_to_observations.hpp"
#include "io/noise_json.hpp"
#include "io/observations_csv.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;
using test::writeFile;

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ObservationsCsv, RoundTripsExactlyEnoughAndKeepsTheOrder) {
  TempDir dir;
  const std::vector<Observation> rows{
      {0, 0, 3, 2.5, -0.25}, {0, 1, -1, 7.123456789012, 3.1}, {4, 0, 12, -0.01, 1e-9}};
  writeObservations(dir / "o.csv", rows);
  std::vector<int> sensors, landmarks;
  const auto back = readObservations(dir / "o.csv", &sensors, &landmarks);
  ASSERT_EQ(back.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(back[i].stop, rows[i].stop);
    EXPECT_EQ(sensors.at(static_cast<std::size_t>(back[i].sensor)), rows[i].sensor);
    EXPECT_EQ(back[i].landmark < 0 ? -1 : landmarks.at(static_cast<std::size_t>(back[i].landmark)),
              rows[i].landmark);
    EXPECT_NEAR(back[i].range_m, rows[i].range_m, 1e-11 * std::max(1.0, std::abs(rows[i].range_m)));
    EXPECT_NEAR(back[i].bearing_rad, rows[i].bearing_rad, 1e-11);
  }
  const std::vector<OdometryStep> odo{{0, 0, 0, 0}, {1, 1.0, -0.5, 0.1}};
  writeOdometry(dir / "d.csv", odo);
  const auto odo_back = readOdometry(dir / "d.csv");
  ASSERT_EQ(odo_back.size(), 2u);
  EXPECT_DOUBLE_EQ(odo_back[1].dy_m, -0.5);
}

TEST(ObservationsCsv, ErrorsNameTheFileLineColumnAndRemedy) {
  TempDir dir;
  const auto f = dir / "o.csv";
  writeFile(f, "stop,sensor,landmark,range_m\n");
  EXPECT_NE(errorOf([&] {
              readObservations(f);
            }).find("line 1: header must be `stop,sensor,landmark,range_m,bearing_rad`"),
            std::string::npos);
  writeFile(f, "stop,sensor,landmark,range_m,bearing_rad\n0,0,1,2.0,0.1\n1,0,1,far,0.1\n");
  const std::string e = errorOf([&] { readObservations(f); });
  EXPECT_NE(e.find(f.string() + ": line 3, column range_m: `far` is not a number"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("docs/FORMAT.md"), std::string::npos) << e;
  writeFile(f, "stop,sensor,landmark,range_m,bearing_rad\n0,0,99999999999,2.0,0.1\n");
  EXPECT_NE(errorOf([&] { readObservations(f); }).find("line 2, column landmark: is too large"),
            std::string::npos);
  writeFile(f, "stop,sensor,landmark,range_m,bearing_rad\n-1,0,1,2.0,0.1\n");
  EXPECT_NE(errorOf([&] { readObservations(f); }).find("line 2, column stop: must be >= 0"),
            std::string::npos);
  writeFile(f, "stop,sensor,landmark,range_m,bearing_rad\n0,0,1,2.0\n");
  EXPECT_NE(errorOf([&] {
              readObservations(f);
            }).find("line 2: expected 5 comma-separated values, found 4"),
            std::string::npos);
  writeFile(f, "stop,sensor,landmark,range_m,bearing_rad\n0,0,1,nan,0.1\n");
  EXPECT_NE(
      errorOf([&] { readObservations(f); }).find("column range_m: `nan` is not a finite number"),
      std::string::npos);
  EXPECT_NE(errorOf([&] { readObservations(dir / "missing.csv"); }).find("file does not exist"),
            std::string::npos);
}

TEST(ObservationsCsv, SensorIdsAreLabelsNumberedInAscendingOrder) {
  TempDir dir;
  const auto f = dir / "o.csv";
  // Sensors 7, -3 and 12 (in file order), landmarks with any ids: -1 stays "unknown".
  writeFile(f,
            "stop,sensor,landmark,range_m,bearing_rad\n0,7,100,1.0,0.1\n0,-3,-5,2.0,0.2\n1,12,-1,3."
            "0,0.3\n"
            "1,7,2000000000,4.0,0.4\n");
  std::vector<int> labels, landmarks;
  const auto rows = readObservations(f, &labels, &landmarks);
  EXPECT_EQ(labels, (std::vector<int>{-3, 7, 12}));
  EXPECT_EQ(landmarks, (std::vector<int>{-5, 100, 2000000000}));
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].sensor, 1);
  EXPECT_EQ(rows[1].sensor, 0);
  EXPECT_EQ(rows[2].sensor, 2);
  EXPECT_EQ(rows[3].sensor, 1);
  EXPECT_EQ(rows[0].landmark, 1);
  EXPECT_EQ(rows[1].landmark, 0);
  EXPECT_EQ(rows[2].landmark, -1);
  EXPECT_EQ(rows[3].landmark, 2);
  // Ids already 0..N-1 keep their numbers.
  writeFile(f, "stop,sensor,landmark,range_m,bearing_rad\n0,1,1,1.0,0.1\n0,0,0,2.0,0.2\n");
  const auto dense = readObservations(f, &labels, &landmarks);
  EXPECT_EQ(labels, (std::vector<int>{0, 1}));
  EXPECT_EQ(landmarks, (std::vector<int>{0, 1}));
  EXPECT_EQ(dense[0].sensor, 1);
  EXPECT_EQ(dense[0].landmark, 1);
  EXPECT_EQ(dense[1].sensor, 0);
  EXPECT_EQ(dense[1].landmark, 0);
}

TEST(OdometryCsv, StopsMustRunFromZeroInOrderAndStopZeroIsTheStart) {
  TempDir dir;
  const auto f = dir / "d.csv";
  writeFile(f, "stop,dx_m,dy_m,dtheta_rad\n0,0,0,0\n2,1,0,0\n");
  EXPECT_NE(errorOf([&] { readOdometry(f); }).find("line 3, column stop: expected stop 1"),
            std::string::npos);
  writeFile(f, "stop,dx_m,dy_m,dtheta_rad\n0,1,0,0\n");
  EXPECT_NE(errorOf([&] { readOdometry(f); }).find("stop 0 is the start"), std::string::npos);
  writeFile(f, "stop,dx_m,dy_m,dtheta_rad\n");
  EXPECT_NE(errorOf([&] { readOdometry(f); }).find("holds no stop"), std::string::npos);
}

TEST(ObservationScene, ParsesRoundTripsAndReportsFieldPaths) {
  TempDir dir;
  writeFile(dir / "s.json", R"({"kind": "observations",
    "sensors": [{"range_var_m2": 0.3, "bearing_var_rad2": 0.4, "range_mean_m": 0.1, "max_range_m": 9, "fov_deg": 180}],
    "process_noise": {"dx_m2": 0.01},
    "landmarks": [{"x_m": 1, "y_m": 2}],
    "trajectory": {"motions": [{"dx_m": 1, "count": 3}, {"dtheta_deg": 90}], "repeat": 2}})");
  EXPECT_EQ(readSceneKind(dir / "s.json"), "observations");
  const ObservationScene s = readObservationScene(dir / "s.json");
  ASSERT_EQ(s.sensors.size(), 1u);
  EXPECT_DOUBLE_EQ(s.sensors[0].noise.range_mean_m, 0.1);
  EXPECT_DOUBLE_EQ(s.sensors[0].max_range_m, 9.0);
  EXPECT_NEAR(s.sensors[0].fov_rad, kPi, 1e-12);
  EXPECT_DOUBLE_EQ(s.process.dx_var_m2, 0.01);
  EXPECT_EQ(s.repeat, 2);
  EXPECT_NEAR(s.motions[1].dtheta_rad, kPi / 2, 1e-12);
  writeTextAtomically(dir / "t.json", observationSceneToJson(s).dump(2));
  const ObservationScene t = readObservationScene(dir / "t.json");
  EXPECT_EQ(observationSceneToJson(t), observationSceneToJson(s));

  writeFile(dir / "bad.json",
            R"({"kind": "observations", "sensors": [{"range_var_m2": -1, "bearing_var_rad2": 0}],
    "landmarks": [{"x_m": 0, "y_m": 0}], "trajectory": {"motions": [{}]}})");
  EXPECT_NE(errorOf([&] {
              readObservationScene(dir / "bad.json");
            }).find("sensors[0].range_var_m2: must not be negative"),
            std::string::npos);
  writeFile(dir / "k.json", R"({"kind": "pictures"})");
  EXPECT_NE(errorOf([&] { readSceneKind(dir / "k.json"); }).find("unknown scene kind 'pictures'"),
            std::string::npos);
}

TEST(NoiseSetting, ReadsWhatItWritesAndRequiresSensorsInOrder) {
  TempDir dir;
  NoiseSetting n;
  n.sensors = {SensorNoise{0.1, 0.2, 0.3, 0.4}, SensorNoise{0, 0.5, 0, 0.6}};
  n.process = ProcessNoise{0.01, 0.02, 0.03};
  writeTextAtomically(dir / "n.json", noiseSettingToJson(n).dump());
  const NoiseSetting back = readNoiseSetting(dir / "n.json");
  ASSERT_EQ(back.sensors.size(), 2u);
  EXPECT_DOUBLE_EQ(back.sensors[0].bearing_var_rad2, 0.4);
  EXPECT_DOUBLE_EQ(back.process.dtheta_var_rad2, 0.03);
  writeFile(dir / "o.json",
            R"({"sensors": [{"sensor": 1, "range_var_m2": 1, "bearing_var_rad2": 1}]})");
  EXPECT_NE(errorOf([&] { readNoiseSetting(dir / "o.json"); }).find("sensors[0].sensor"),
            std::string::npos);
}

TEST(LandmarksToObservations, ConvertsRangesToTheCentreOrTheSurfaceAndStopPosesToMotions) {
  TempDir dir;
  writeFile(dir / "l.csv",
            "file,stop,landmark,bearing_rad,range_m,centre_x_m,centre_y_m,radius_m,n_points,rms_m\n"
            "scan_000010.pcd,1,2,0.5,3.0,0,0,0.12,20,0.01\n"
            "scan_000000.pcd,0,1,-0.5,2.0,0,0,0.10,18,0.01\n");
  const auto centre = observationsFromLandmarksCsv(dir / "l.csv", RangeReference::centre);
  ASSERT_EQ(centre.size(), 2u);
  EXPECT_EQ(centre[0].stop, 0);  // sorted by stop
  EXPECT_EQ(centre[0].landmark, 1);
  EXPECT_EQ(centre[1].landmark, 2);
  EXPECT_DOUBLE_EQ(centre[1].range_m, 3.0);
  EXPECT_DOUBLE_EQ(centre[1].bearing_rad, 0.5);
  const auto surface = observationsFromLandmarksCsv(dir / "l.csv", RangeReference::surface);
  EXPECT_DOUBLE_EQ(surface[1].range_m, 3.0 - 0.12);
  // One reader for landmarks.csv: its header and its ids (>= 1) as `detect` writes them.
  writeFile(dir / "m.csv", "file,stop,landmark,range_m\nx,0,1,2\n");
  EXPECT_NE(errorOf([&] {
              observationsFromLandmarksCsv(dir / "m.csv", RangeReference::centre);
            }).find("header must be"),
            std::string::npos);
  writeFile(dir / "z.csv",
            "file,stop,landmark,bearing_rad,range_m,centre_x_m,centre_y_m,radius_m,n_points,rms_m\n"
            "scan_000000.pcd,0,0,-0.5,2.0,0,0,0.10,18,0.01\n");
  EXPECT_NE(errorOf([&] {
              observationsFromLandmarksCsv(dir / "z.csv", RangeReference::centre);
            }).find("column landmark"),
            std::string::npos);

  std::vector<Stop> stops(3);
  stops[0].commanded = Pose2{1.0, 1.0, kPi / 2};
  stops[1].commanded = Pose2{1.0, 2.0, kPi / 2};  // 1 m forward
  stops[2].commanded = Pose2{0.0, 2.0, kPi};      // 1 m to the left, turned 90 degrees
  const auto odo = odometryFromStops(stops);
  ASSERT_EQ(odo.size(), 3u);
  EXPECT_DOUBLE_EQ(odo[0].dx_m, 0.0);
  EXPECT_NEAR(odo[1].dx_m, 1.0, 1e-12);
  EXPECT_NEAR(odo[1].dy_m, 0.0, 1e-12);
  EXPECT_NEAR(odo[2].dx_m, 0.0, 1e-12);
  EXPECT_NEAR(odo[2].dy_m, 1.0, 1e-12);
  EXPECT_NEAR(odo[2].dtheta_rad, kPi / 2, 1e-12);
}

}  // namespace
}  // namespace lidarcal::io
