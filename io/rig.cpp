// SPDX-License-Identifier: BSD-3-Clause
#include "io/rig.hpp"

#include <cmath>
#include <cstdio>
#include <map>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/csv_row.hpp"
#include "io/json_util.hpp"

namespace lidarcal::io {
namespace {

namespace fs = std::filesystem;
using ojson = nlohmann::ordered_json;

constexpr const char* kFormat = "lidarcal-rig/1";
constexpr const char* kScansHeader =
    "sensor,file,stamp_s,input,stop,vehicle_x_m,vehicle_y_m,vehicle_yaw_rad";
constexpr const char* kRemedy =
    "rig sequences are written by `lidarcal import` with several topics (docs/FORMAT.md)";

/// Text of a double that reads back as the same double.
std::string exact(double v) {
  if (!std::isfinite(v)) return "nan";
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

}  // namespace

std::optional<std::size_t> RigMeta::find(const std::string& key) const {
  return findSensorByKey(sensors, key);
}

Mounting readMounting(const JsonView& v) {
  v.requireObject();
  Mounting m;
  m.x_m = v.getNumber("x_m");
  m.y_m = v.getNumber("y_m");
  m.yaw_rad = v.getNumber("yaw_rad");
  m.upside_down = v.getBool("upside_down", false);
  m.z_m = v.getNumber("z_m", 0.0);
  return m;
}

ojson mountingJson(const Mounting& m) {
  return ojson{{"x_m", m.x_m},
               {"y_m", m.y_m},
               {"yaw_rad", m.yaw_rad},
               {"upside_down", m.upside_down},
               {"z_m", m.z_m}};
}

bool isRigDirectory(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir, ec) && fs::is_regular_file(dir / "rig.json", ec);
}

void writeRigMeta(const fs::path& file, const RigMeta& meta) {
  ojson sensors = ojson::array();
  for (const RigSensorInfo& s : meta.sensors) {
    ojson j{{"name", s.name}, {"topic", s.topic}, {"frame_id", s.frame_id}};
    j["mounting"] = s.mounting ? mountingJson(*s.mounting) : ojson(nullptr);
    sensors.push_back(j);
  }
  ojson inputs = ojson::array();
  for (const RigInput& in : meta.inputs) {
    ojson m = ojson::object();
    for (const auto& [name, mounting] : in.mountings) m[name] = mountingJson(mounting);
    inputs.push_back(ojson{{"name", in.name}, {"mountings", m}});
  }
  const ojson j{{"format", kFormat},
                {"vehicle_frame", meta.vehicle_frame},
                {"vehicle_poses", meta.pose_source},
                {"sensors", sensors},
                {"inputs", inputs}};
  writeTextAtomically(file, j.dump(2) + "\n");
}

RigMeta readRigMeta(const fs::path& file) {
  const nlohmann::json j = readJsonFile(file);
  const JsonView root(file.string(), j);
  root.requireObject();
  if (root.getString("format", "") != kFormat)
    root.fail("format",
              std::string("not a rig sequence (expected \"") + kFormat + "\"); " + kRemedy);
  RigMeta meta;
  meta.vehicle_frame = root.getString("vehicle_frame", "");
  meta.pose_source = root.getString("vehicle_poses", "none");
  for (const JsonView& s : root.array("sensors")) {
    s.requireObject();
    RigSensorInfo info;
    info.name = s.getString("name");
    if (info.name.empty() || info.name.find_first_of("/\\,") != std::string::npos ||
        info.name[0] == '.')
      s.fail("name", "must be a plain directory name (no '/', '\\\\', ',' or leading '.')");
    info.topic = s.getString("topic", "");
    info.frame_id = s.getString("frame_id", "");
    if (s.has("mounting") && !s.json().at("mounting").is_null())
      info.mounting = readMounting(s.child("mounting"));
    if (meta.find(info.name)) s.fail("name", "names a sensor twice");
    meta.sensors.push_back(info);
  }
  if (meta.sensors.empty()) root.fail("sensors", "lists no sensor");
  if (root.has("inputs"))
    for (const JsonView& in : root.array("inputs")) {
      in.requireObject();
      RigInput input;
      input.name = in.getString("name", "");
      if (in.has("mountings")) {
        const JsonView m = in.child("mountings");
        m.requireObject();
        for (const auto& [name, value] : m.json().items())
          input.mountings[name] = readMounting(m.child(name));
      }
      meta.inputs.push_back(input);
    }
  return meta;
}

void writeRigScans(const fs::path& file, const std::vector<RigScan>& scans) {
  std::string text = std::string(kScansHeader) + "\n";
  for (const RigScan& s : scans)
    text += s.sensor + "," + s.file + "," + exact(s.stamp_s) + "," + std::to_string(s.input) + "," +
            std::to_string(s.stop) + "," + exact(s.vehicle.x_m) + "," + exact(s.vehicle.y_m) + "," +
            exact(s.vehicle.yaw_rad) + "\n";
  writeTextAtomically(file, text);
}

std::vector<RigScan> readRigScans(const fs::path& file) {
  CsvReader csv(file, kRemedy);
  csv.expectHeader(kScansHeader);
  std::vector<RigScan> out;
  while (csv.next(8)) {
    RigScan s;
    s.sensor = csv.text(0);
    s.file = csv.text(1);
    s.stamp_s = csv.text(2) == "nan" ? std::nan("") : csv.number(2, "stamp_s");
    const long long input = csv.integer(3, "input"), stop = csv.integer(4, "stop");
    if (input < 0 || stop < 0) csv.fail(input < 0 ? "input" : "stop", "must be >= 0");
    s.input = static_cast<std::size_t>(input);
    s.stop = static_cast<std::size_t>(stop);
    s.vehicle = Pose2{csv.number(5, "vehicle_x_m"), csv.number(6, "vehicle_y_m"),
                      csv.number(7, "vehicle_yaw_rad")};
    if (!out.empty() && s.stop < out.back().stop && s.sensor == out.back().sensor)
      csv.fail("stop", "goes back: a sensor's scans are listed in time order, stops counted up");
    out.push_back(s);
  }
  return out;
}

Rig openRig(const fs::path& dir) {
  Rig rig;
  rig.dir = dir;
  rig.meta = readRigMeta(dir / "rig.json");
  rig.scans = readRigScans(dir / "scans.csv");
  std::vector<std::map<std::string, std::size_t>> index_of(rig.meta.sensors.size());
  for (std::size_t s = 0; s < rig.meta.sensors.size(); ++s) {
    rig.sequences.push_back(openSequence(dir / rig.meta.sensors[s].name));
    const Sequence& seq = rig.sequences.back();
    for (std::size_t i = 0; i < seq.scans.size(); ++i)
      index_of[s][fs::path(seq.scans.path(i)).filename().string()] = i;
  }
  std::vector<std::size_t> listed(rig.meta.sensors.size(), 0);
  for (std::size_t r = 0; r < rig.scans.size(); ++r) {
    const RigScan& row = rig.scans[r];
    const std::string where = "row " + std::to_string(r + 2);
    const std::optional<std::size_t> s = rig.meta.find(row.sensor);
    if (!s || rig.meta.sensors[*s].name != row.sensor)
      throw InputError((dir / "scans.csv").string(), where,
                       "names sensor '" + row.sensor + "', which rig.json does not list", kRemedy);
    const auto it = index_of[*s].find(row.file);
    if (it == index_of[*s].end())
      throw InputError((dir / "scans.csv").string(), where,
                       "names scan " + row.sensor + "/" + row.file + ", which does not exist",
                       "restore the scan or import the recordings again");
    if (!rig.meta.inputs.empty() && row.input >= rig.meta.inputs.size())
      throw InputError((dir / "scans.csv").string(), where,
                       "names recording " + std::to_string(row.input) + " of " +
                           std::to_string(rig.meta.inputs.size()),
                       kRemedy);
    rig.scan_index.push_back(it->second);
    ++listed[*s];
  }
  for (std::size_t s = 0; s < listed.size(); ++s)
    if (listed[s] != rig.sequences[s].scans.size())
      throw InputError((dir / "scans.csv").string(), rig.meta.sensors[s].name,
                       "lists " + std::to_string(listed[s]) + " of the sensor's " +
                           std::to_string(rig.sequences[s].scans.size()) + " scans",
                       "every scan of every sensor has one row; import the recordings again");
  return rig;
}

}  // namespace lidarcal::io
