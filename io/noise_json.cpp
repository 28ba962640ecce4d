// SPDX-License-Identifier: BSD-3-Clause
#include "io/noise_json.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_util.hpp"

namespace lidarcal::io {
namespace {

using ojson = nlohmann::ordered_json;

SensorNoise parseSensorNoise(const JsonView& v) {
  SensorNoise n;
  n.range_mean_m = v.getNumber("range_mean_m", 0.0);
  n.range_var_m2 = v.getNonNegative("range_var_m2");
  n.bearing_mean_rad = v.getNumber("bearing_mean_rad", 0.0);
  n.bearing_var_rad2 = v.getNonNegative("bearing_var_rad2");
  return n;
}

ProcessNoise parseProcessVar(const JsonView& v) {
  ProcessNoise p;
  p.dx_var_m2 = v.getNonNegative("dx_m2", 0.0);
  p.dy_var_m2 = v.getNonNegative("dy_m2", 0.0);
  p.dtheta_var_rad2 = v.getNonNegative("dtheta_rad2", 0.0);
  return p;
}

ojson sensorNoiseToJson(const SensorNoise& n) {
  return ojson{{"range_mean_m", n.range_mean_m},
               {"range_var_m2", n.range_var_m2},
               {"bearing_mean_rad", n.bearing_mean_rad},
               {"bearing_var_rad2", n.bearing_var_rad2}};
}

ojson processVarToJson(const ProcessNoise& p) {
  return ojson{{"dx_m2", p.dx_var_m2}, {"dy_m2", p.dy_var_m2}, {"dtheta_rad2", p.dtheta_var_rad2}};
}

ObservationScene parseObservationScene(const JsonView& root) {
  root.requireObject();
  if (root.getString("kind", "scans") != "observations")
    root.fail("kind", "must be \"observations\" for an observation scene");
  ObservationScene s;
  s.name = root.getString("name", s.name);
  for (const auto& e : root.array("sensors")) {
    e.requireObject();
    RangeBearingSensor sensor;
    sensor.name = e.getString("name", "sensor " + std::to_string(s.sensors.size()));
    sensor.noise = parseSensorNoise(e);
    sensor.min_range_m = e.getNonNegative("min_range_m", 0.0);
    sensor.max_range_m = e.getPositive("max_range_m", sensor.max_range_m);
    if (sensor.min_range_m >= sensor.max_range_m)
      e.fail("min_range_m", "must be smaller than max_range_m");
    sensor.fov_rad = deg2rad(e.getPositive("fov_deg", 360.0));
    if (sensor.fov_rad > 2.0 * kPi + 1e-12) e.fail("fov_deg", "must not exceed 360");
    s.sensors.push_back(sensor);
  }
  if (s.sensors.empty()) root.fail("sensors", "must list at least one sensor");
  if (root.has("process_noise")) s.process = parseProcessVar(root.child("process_noise"));
  for (const auto& e : root.array("landmarks")) {
    e.requireObject();
    s.landmarks.push_back(PointLandmark{e.getNumber("x_m"), e.getNumber("y_m")});
  }
  if (s.landmarks.empty()) root.fail("landmarks", "must list at least one landmark");
  const JsonView traj = root.child("trajectory");
  if (traj.has("start")) {
    const JsonView st = traj.child("start");
    s.start.x_m = st.getNumber("x_m", 0.0);
    s.start.y_m = st.getNumber("y_m", 0.0);
    s.start.yaw_rad = deg2rad(st.getNumber("yaw_deg", 0.0));
  }
  for (const auto& e : traj.array("motions")) {
    e.requireObject();
    MotionSpec m;
    m.dx_m = e.getNumber("dx_m", 0.0);
    m.dy_m = e.getNumber("dy_m", 0.0);
    m.dtheta_rad = deg2rad(e.getNumber("dtheta_deg", 0.0));
    m.count = e.getPositiveInt("count", 1);
    s.motions.push_back(m);
  }
  if (s.motions.empty()) traj.fail("motions", "must list at least one motion");
  s.repeat = traj.getPositiveInt("repeat", 1);
  long long stops = 1;
  for (const auto& m : s.motions) stops += static_cast<long long>(m.count) * s.repeat;
  if (stops > 10'000'000) traj.fail("repeat", "more than 10 million stops");
  return s;
}

NoiseSetting parseNoiseSetting(const JsonView& root, const std::vector<int>* labels) {
  root.requireObject();
  NoiseSetting n;
  const auto sensors = root.array("sensors");
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    sensors[i].requireObject();
    const int label = labels && i < labels->size() ? (*labels)[i] : static_cast<int>(i);
    if (sensors[i].getInt("sensor", label) != label)
      sensors[i].fail(
          "sensor",
          labels
              ? "sensors must be listed in the ascending order of their ids in the observations (" +
                    std::to_string(label) + " here)"
              : "sensors must be listed in order 0, 1, 2, ...");
    n.sensors.push_back(parseSensorNoise(sensors[i]));
  }
  if (root.has("process_var")) n.process = parseProcessVar(root.child("process_var"));
  return n;
}

}  // namespace

std::string readSceneKind(const std::filesystem::path& file) {
  const nlohmann::json j = readJsonFile(file);
  const JsonView root(file.string(), j);
  root.requireObject();
  const std::string kind = root.getString("kind", "scans");
  if (kind != "scans" && kind != "observations")
    root.fail("kind", "unknown scene kind '" + kind + "' (expected \"scans\" or \"observations\")");
  return kind;
}

ObservationScene readObservationScene(const std::filesystem::path& file) {
  const nlohmann::json j = readJsonFile(file);
  return parseObservationScene(JsonView(file.string(), j));
}

ojson observationSceneToJson(const ObservationScene& s) {
  ojson sensors = ojson::array();
  for (const auto& e : s.sensors) {
    ojson j{{"name", e.name}};
    j.update(sensorNoiseToJson(e.noise));
    j["min_range_m"] = e.min_range_m;
    if (std::isfinite(e.max_range_m)) j["max_range_m"] = e.max_range_m;
    j["fov_deg"] = rad2deg(e.fov_rad);
    sensors.push_back(j);
  }
  ojson landmarks = ojson::array();
  for (const auto& l : s.landmarks) landmarks.push_back(ojson{{"x_m", l.x_m}, {"y_m", l.y_m}});
  ojson motions = ojson::array();
  for (const auto& m : s.motions)
    motions.push_back(ojson{{"dx_m", m.dx_m},
                            {"dy_m", m.dy_m},
                            {"dtheta_deg", rad2deg(m.dtheta_rad)},
                            {"count", m.count}});
  return ojson{{"kind", "observations"},
               {"name", s.name},
               {"sensors", sensors},
               {"process_noise", processVarToJson(s.process)},
               {"landmarks", landmarks},
               {"trajectory", ojson{{"start", ojson{{"x_m", s.start.x_m},
                                                    {"y_m", s.start.y_m},
                                                    {"yaw_deg", rad2deg(s.start.yaw_rad)}}},
                                    {"motions", motions},
                                    {"repeat", s.repeat}}}};
}

ojson noiseSettingToJson(const NoiseSetting& setting) {
  ojson sensors = ojson::array();
  for (std::size_t i = 0; i < setting.sensors.size(); ++i) {
    ojson j{{"sensor", i}};
    j.update(sensorNoiseToJson(setting.sensors[i]));
    sensors.push_back(j);
  }
  return ojson{{"sensors", sensors}, {"process_var", processVarToJson(setting.process)}};
}

NoiseSetting readNoiseSetting(const std::filesystem::path& file,
                              const std::vector<int>* sensor_labels) {
  const nlohmann::json j = readJsonFile(file);
  return parseNoiseSetting(JsonView(file.string(), j), sensor_labels);
}

void writeNoiseTruth(const std::filesystem::path& file, const NoiseTruth& t) {
  ojson landmarks = ojson::array();
  for (std::size_t i = 0; i < t.scene.landmarks.size(); ++i)
    landmarks.push_back(
        ojson{{"id", i}, {"x_m", t.scene.landmarks[i].x_m}, {"y_m", t.scene.landmarks[i].y_m}});
  ojson poses = ojson::array();
  for (std::size_t k = 0; k < t.poses.size(); ++k)
    poses.push_back(ojson{{"stop", k},
                          {"x_m", t.poses[k].x_m},
                          {"y_m", t.poses[k].y_m},
                          {"yaw_rad", t.poses[k].yaw_rad}});
  ojson j{{"format", "lidarcal-noise-truth/1"}, {"seed", t.seed}};
  j.update(noiseSettingToJson(trueNoise(t.scene)));
  j["landmarks"] = landmarks;
  j["poses"] = poses;
  j["scene"] = observationSceneToJson(t.scene);
  writeTextAtomically(file, j.dump(2) + "\n");
}

NoiseTruth readNoiseTruth(const std::filesystem::path& file) {
  const nlohmann::json j = readJsonFile(file);
  const JsonView root(file.string(), j);
  root.requireObject();
  if (root.getString("format", "") != "lidarcal-noise-truth/1")
    root.fail("format", "not a lidarcal noise truth file (expected \"lidarcal-noise-truth/1\")");
  NoiseTruth t;
  const auto& seed = j.at("seed");
  if (!seed.is_number_unsigned()) root.fail("seed", "must be a non-negative integer");
  t.seed = seed.get<std::uint64_t>();
  t.scene = parseObservationScene(root.child("scene"));
  for (const auto& e : root.array("poses")) {
    e.requireObject();
    t.poses.push_back(Pose2{e.getNumber("x_m"), e.getNumber("y_m"), e.getNumber("yaw_rad")});
  }
  return t;
}

}  // namespace lidarcal::io
