// SPDX-License-Identifier: BSD-3-Clause
#include "io/rig_model_io.hpp"

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_number.hpp"
#include "io/json_util.hpp"
#include "io/model_io.hpp"
#include "io/rig.hpp"

namespace lidarcal::io {
namespace {

using ojson = nlohmann::ordered_json;
constexpr const char* kFormat = "lidarcal-rig-model/1";

ojson poseJson(const Pose2& p) {
  return ojson{{"x_m", p.x_m}, {"y_m", p.y_m}, {"yaw_rad", p.yaw_rad}};
}

/// Standard errors of (x, y, yaw) from a row-major 3x3 covariance, in mm and degrees.
ojson standardErrors(const std::array<double, 9>& c) {
  return ojson{{"x_mm", jsonNumber(1000.0 * std::sqrt(c[0]))},
               {"y_mm", jsonNumber(1000.0 * std::sqrt(c[4]))},
               {"yaw_deg", jsonNumber(rad2deg(std::sqrt(c[8])))}};
}

Pose2 readPose(const JsonView& v) {
  return Pose2{v.getNumber("x_m"), v.getNumber("y_m"), v.getNumber("yaw_rad")};
}

std::array<double, 9> readCovariance(const JsonView& v, const std::string& key) {
  std::array<double, 9> c{};
  if (!v.has(key)) return c;
  const std::vector<double> x = v.getNumbers(key);
  if (x.size() != 9) v.fail(key, "must hold 9 numbers (a row-major 3x3 covariance)");
  std::copy(x.begin(), x.end(), c.begin());
  return c;
}

std::string blockNames(const RigModel& m) {
  std::string names;
  for (const auto& s : m.sensors)
    names += (names.empty() ? "" : ", ") + s.name + (s.topic.empty() ? "" : " (" + s.topic + ")");
  return names;
}

}  // namespace

std::optional<std::size_t> RigModel::find(const std::string& key) const {
  return findSensorByKey(sensors, key);
}

bool isRigModel(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return false;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_object() && j.contains("format") && j["format"] == kFormat;
}

void writeRigModel(const std::filesystem::path& file, const RigModel& m) {
  ojson sensors = ojson::array();
  for (const RigModelSensor& s : m.sensors) {
    ojson mounting = mountingJson(s.mounting);
    mounting["held"] = s.mounting_held;
    mounting["standard_error"] = standardErrors(s.mounting_covariance);
    mounting["covariance"] = s.mounting_covariance;
    sensors.push_back(ojson{{"name", s.name},
                            {"topic", s.topic},
                            {"frame_id", s.frame_id},
                            {"mounting", mounting},
                            {"design", s.design ? mountingJson(*s.design) : ojson(nullptr)},
                            {"beam_scatter_m", s.beam_scatter_m},
                            {"model", modelJson(s.model)}});
  }
  ojson relative = ojson::array();
  for (const RigModelRelative& r : m.relative) {
    ojson j{{"reference", r.reference},  {"sensor", r.sensor},
            {"x_m", r.pose.x_m},         {"y_m", r.pose.y_m},
            {"yaw_rad", r.pose.yaw_rad}, {"standard_error", standardErrors(r.covariance)},
            {"covariance", r.covariance}};
    j["design"] = r.design ? poseJson(*r.design) : ojson(nullptr);
    if (r.design)
      j["difference"] = ojson{{"x_mm", 1000.0 * (r.pose.x_m - r.design->x_m)},
                              {"y_mm", 1000.0 * (r.pose.y_m - r.design->y_m)},
                              {"yaw_deg", rad2deg(wrapAngle(r.pose.yaw_rad - r.design->yaw_rad))}};
    relative.push_back(j);
  }
  ojson poles = ojson::array();
  for (const auto& p : m.poles)
    poles.push_back(
        ojson{{"id", p.id},
              {"x_m", p.x_m},
              {"y_m", p.y_m},
              {"covariance_m2",
               ojson::array({jsonNumber(p.covariance_m2[0]), jsonNumber(p.covariance_m2[1]),
                             jsonNumber(p.covariance_m2[2]), jsonNumber(p.covariance_m2[3])})},
              {"sensors", p.sensors}});
  ojson stops = ojson::array();
  for (const Pose2& p : m.stops) stops.push_back(poseJson(p));
  const ojson j{{"format", kFormat},
                {"frame", m.frame},
                {"reference", m.reference},
                {"vehicle_frame", m.vehicle_frame},
                {"scale_free", m.scale_free},
                {"motion_prior", m.motion_prior},
                {"radius_m", m.radius_m},
                {"sensors", sensors},
                {"relative_mountings", relative},
                {"poles", poles},
                {"stops", stops},
                {"notes", m.notes},
                {"diagnostics", ojson{{"status", m.status.name()}, {"message", m.status.message}}}};
  writeTextAtomically(file, j.dump(2) + "\n");
}

RigModel readRigModel(const std::filesystem::path& file) {
  const nlohmann::json j = readJsonFile(file);
  const JsonView root(file.string(), j);
  root.requireObject();
  if (root.getString("format", "") != kFormat)
    root.fail("format", std::string("not a rig model (expected \"") + kFormat +
                            "\"); `lidarcal calibrate RIG` writes one");
  RigModel m;
  m.frame = root.getString("frame", "relative");
  m.reference = root.getString("reference", "");
  m.vehicle_frame = root.getString("vehicle_frame", "");
  m.scale_free = root.getBool("scale_free", false);
  m.motion_prior = root.getBool("motion_prior", false);
  m.radius_m = root.getNonNegative("radius_m", 0.0);
  const std::vector<JsonView> blocks = root.array("sensors");
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    const JsonView& b = blocks[k];
    b.requireObject();
    RigModelSensor s;
    s.name = b.getString("name");
    s.topic = b.getString("topic", "");
    s.frame_id = b.getString("frame_id", "");
    const JsonView mounting = b.child("mounting");
    s.mounting = readMounting(mounting);
    s.mounting_held = mounting.getBool("held", false);
    s.mounting_covariance = readCovariance(mounting, "covariance");
    if (b.has("design") && !b.json().at("design").is_null())
      s.design = readMounting(b.child("design"));
    s.beam_scatter_m = b.getNonNegative("beam_scatter_m", 0.0);
    s.model = modelFromJson(b.json().at("model"), file.string(), b.pathOf("model"));
    if (m.find(s.name)) b.fail("name", "names a sensor twice");
    m.sensors.push_back(std::move(s));
  }
  if (m.sensors.empty()) root.fail("sensors", "holds no sensor");
  if (root.has("relative_mountings"))
    for (const JsonView& r : root.array("relative_mountings")) {
      RigModelRelative rel;
      rel.reference = r.getString("reference");
      rel.sensor = r.getString("sensor");
      rel.pose = readPose(r);
      rel.covariance = readCovariance(r, "covariance");
      if (r.has("design") && !r.json().at("design").is_null())
        rel.design = readPose(r.child("design"));
      m.relative.push_back(rel);
    }
  if (root.has("notes"))
    for (const JsonView& n : root.array("notes"))
      if (n.json().is_string()) m.notes.push_back(n.json().get<std::string>());
  return m;
}

CalibrationModel readModelFor(const std::filesystem::path& file, const std::string& key,
                              std::string* chosen) {
  if (!isRigModel(file)) {
    if (chosen) chosen->clear();
    return readModel(file);
  }
  const RigModel rig = readRigModel(file);
  if (key.empty())
    throw InputError(file.string(), "sensors", "holds a model per sensor (" + blockNames(rig) + ")",
                     "pick one with --sensor NAME or TOPIC");
  const std::optional<std::size_t> at = rig.find(key);
  if (!at)
    throw InputError(file.string(), "sensors",
                     "has no sensor named '" + key + "' (it holds " + blockNames(rig) + ")",
                     "pick one by its name, topic or frame");
  if (chosen) *chosen = rig.sensors[*at].name;
  return rig.sensors[*at].model;
}

CalibrationModel readModelForNode(const std::filesystem::path& file,
                                  const std::optional<std::string>& sensor_name,
                                  const std::string& topic, std::string* chosen) {
  if (!isRigModel(file)) {
    if (chosen) chosen->clear();
    return readModel(file);
  }
  const RigModel rig = readRigModel(file);
  const std::optional<std::size_t> at = rig.find(sensor_name ? *sensor_name : topic);
  if (!at && sensor_name)
    throw InputError(
        file.string(), "sensors",
        "has no block for sensor_name '" + *sensor_name + "' (it holds " + blockNames(rig) + ")",
        "set sensor_name to one of these names, or leave it unset to pick the block by the input "
        "topic");
  if (!at)
    throw InputError(file.string(), "sensors",
                     "has no block whose topic is the input topic '" + topic + "' (it holds " +
                         blockNames(rig) + ")",
                     "set sensor_name to the block's name, or the input to its topic");
  if (chosen) *chosen = rig.sensors[*at].name;
  return rig.sensors[*at].model;
}

}  // namespace lidarcal::io
