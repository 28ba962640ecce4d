// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/rig_import.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <set>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/import_rosbag.hpp"
#include "io/import_rosbag2.hpp"
#include "io/pose_track.hpp"

namespace lidarcal::pipeline {
namespace {

void checkSettings(const RigImportSettings& s, const std::vector<std::string>& names) {
  if (!isBag(s.base.format))
    throw InputError("", "--topic", "several topics are read from ROS1 or ROS 2 bags only",
                     "import one topic at a time");
  if (s.topics.size() < 2)
    throw InputError("", "--topic", "a rig needs two topics or more", "list them: --topic /a,/b");
  if (names.size() != s.topics.size())
    throw InputError("", "--sensor-names",
                     "gives " + std::to_string(names.size()) + " names for " +
                         std::to_string(s.topics.size()) + " topics",
                     "one name per topic, in the same order");
  std::set<std::string> seen_topics, seen_names;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (!seen_topics.insert(s.topics[k]).second)
      throw InputError("", "--topic " + s.topics[k], "is listed twice", "list each topic once");
    const std::string& n = names[k];
    if (n.empty() || n[0] == '.' || n.find_first_of("/\\,") != std::string::npos ||
        !seen_names.insert(n).second)
      throw InputError("", "--sensor-names " + n,
                       "must be distinct plain names (no '/', '\\', ',' or leading '.')",
                       "e.g. --sensor-names front,back");
  }
  if (!s.base.sensor_name.empty())
    throw InputError("", "--sensor-name", "names one sensor; a rig names each",
                     "use --sensor-names front,back");
}

/// The vehicle's stops over the rig's rows: a new stop at every recording, and within one, when
/// the vehicle's recorded pose leaves the tolerances of the stop's first pose.
std::size_t assignStops(std::vector<io::RigScan>& rows, const io::BagPoseConfig& pose, bool known) {
  std::vector<std::size_t> order(rows.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return rows[a].input != rows[b].input ? rows[a].input < rows[b].input
                                          : rows[a].stamp_s < rows[b].stamp_s;
  });
  std::size_t stop = 0, input = 0;
  bool first = true;
  std::unique_ptr<io::StillPoseFilter> still;
  for (const std::size_t i : order) {
    if (first || rows[i].input != input) {
      if (!first) ++stop;
      input = rows[i].input;
      still = std::make_unique<io::StillPoseFilter>(pose.still_m, pose.still_rad);
      if (known) still->apply(rows[i].vehicle);
      first = false;
    }
    if (known) {
      const std::size_t before = still->stops();
      rows[i].vehicle = still->apply(rows[i].vehicle);
      if (still->stops() != before) ++stop;
    }
    rows[i].stop = stop;
  }
  return rows.empty() ? 0 : stop + 1;
}

std::string describe(const Mounting& m) {
  char text[160];
  std::snprintf(text, sizeof text, "x %.4f m, y %.4f m, yaw %.2f deg%s", m.x_m, m.y_m,
                rad2deg(m.yaw_rad), m.upside_down ? ", upside down" : "");
  return text;
}

/// One topic of one recording: which recording, which sensor.
struct TopicSource {
  std::size_t input, sensor;
  const std::string& name;  ///< the sensor's name
};

/// What reading the topics builds: a row per scan written and the rig's facts.
struct RigRows {
  std::vector<io::RigScan> rows;
  io::RigMeta& meta;
  bool missing_pose = false;  ///< a scan without the vehicle's pose (with --pose)
};

/// Reads one topic of one recording into the sensor's writer and the rows.
io::ImportReport readTopic(const RigImportSettings& s, const TopicSource& t,
                           io::SequenceWriter& writer, io::RigInput& record, RigRows& out,
                           const std::function<void(double)>& progress) {
  const std::size_t input = t.input;
  const std::string& name = t.name;
  io::RigMeta& meta = out.meta;
  io::RigSensorInfo& info = meta.sensors[t.sensor];
  io::RosbagConfig c;
  c.topic = s.topics[t.sensor];
  c.range_min_m = s.base.range_min_m;
  c.range_max_m = s.base.range_max_m;
  c.pose = s.base.bag_pose;
  c.pose.vehicle_frame = s.vehicle_frame;
  const auto on_scan = [&](const io::RawScan& scan) {
    const std::size_t before = writer.summary().written;
    const bool more = writer.add(scan);
    if (writer.summary().written != before) {
      io::RigScan row;
      row.sensor = name;
      row.file = io::scanFileName(before);
      row.stamp_s = scan.stamp_s;
      row.input = input;
      if (scan.vehicle_pose) row.vehicle = *scan.vehicle_pose;
      out.missing_pose =
          out.missing_pose ||
          (s.base.bag_pose.kind != io::BagPoseConfig::Kind::none && !scan.vehicle_pose);
      out.rows.push_back(row);
      if (scan.mounting && !record.mountings.count(name)) record.mountings[name] = *scan.mounting;
      if (info.frame_id.empty()) info.frame_id = scan.frame_id;
      if (meta.vehicle_frame.empty()) meta.vehicle_frame = scan.vehicle_frame;
      if (scan.vehicle_frame != meta.vehicle_frame)
        throw InputError(s.base.inputs[input].string(), "topic " + c.topic,
                         "its frame " + scan.frame_id + " rides on " + scan.vehicle_frame +
                             ", another sensor's on " + meta.vehicle_frame,
                         "name the vehicle's frame with --vehicle-frame");
    }
    if (progress) progress(scan.progress);
    return more;
  };
  const std::filesystem::path& bag = s.base.inputs[input];
  return s.base.format == ImportFormat::rosbag1 ? io::readRosbag(bag, c, on_scan)
                                                : io::readRosbag2(bag, c, on_scan);
}

/// Each sensor's designed mounting: the first recording's from /tf_static, with a note where a
/// later recording gives another or none is given.
void noteMountings(const std::vector<std::string>& names, RigImportResult& result) {
  for (std::size_t k = 0; k < names.size(); ++k) {
    for (const io::RigInput& in : result.meta.inputs)
      if (const auto it = in.mountings.find(names[k]); it != in.mountings.end()) {
        if (!result.meta.sensors[k].mounting)
          result.meta.sensors[k].mounting = it->second;
        else if (std::abs(it->second.x_m - result.meta.sensors[k].mounting->x_m) > 1e-6 ||
                 std::abs(it->second.y_m - result.meta.sensors[k].mounting->y_m) > 1e-6 ||
                 std::abs(it->second.yaw_rad - result.meta.sensors[k].mounting->yaw_rad) > 1e-9)
          result.notes.push_back(names[k] + ": tf_static gives another mounting in " + in.name +
                                 " (" + describe(it->second) + ") than in the first recording (" +
                                 describe(*result.meta.sensors[k].mounting) +
                                 "): rig.json keeps each");
      }
    if (!result.meta.sensors[k].mounting)
      result.notes.push_back(
          names[k] +
          ": no mounting in /tf_static (the calibration starts from the identity; "
          "give the mountings' designs with --mount at calibrate)");
  }
}

}  // namespace

std::vector<std::string> sensorNamesFromTopics(const std::vector<std::string>& topics) {
  std::vector<std::string> names;
  for (std::string t : topics) {
    while (!t.empty() && t.front() == '/') t.erase(0, 1);
    std::replace(t.begin(), t.end(), '/', '_');
    names.push_back(t);
  }
  return names;
}

RigImportResult importRig(const RigImportSettings& s,
                          const std::function<void(double)>& on_progress) {
  const std::vector<std::string> names =
      s.names.empty() ? sensorNamesFromTopics(s.topics) : s.names;
  checkSettings(s, names);
  if (s.base.inputs.empty())
    throw InputError("", "INPUT", "no recording given", "name one or more bags to import");
  for (const auto& input : s.base.inputs) {
    if (s.base.format == ImportFormat::rosbag1) io::requireRosbagSupport(input);
    io::checkOutsideInput(input, s.base.out);
  }
  io::StagedDirectory staged(s.base.out, s.base.writer.overwrite);
  RigImportResult result;
  std::vector<std::unique_ptr<io::SequenceWriter>> writers;
  io::SequenceWriterConfig wc = s.base.writer;
  wc.overwrite = false;
  for (std::size_t k = 0; k < names.size(); ++k) {
    writers.push_back(std::make_unique<io::SequenceWriter>(staged.path() / names[k], wc));
    result.meta.sensors.push_back(io::RigSensorInfo{names[k], s.topics[k], "", std::nullopt});
  }
  result.read.resize(names.size());
  RigRows out{{}, result.meta};
  const double share = 1.0 / static_cast<double>(s.base.inputs.size() * names.size());
  for (std::size_t in = 0; in < s.base.inputs.size(); ++in) {
    io::RigInput record;
    record.name = s.base.inputs[in].filename().string();
    for (std::size_t k = 0; k < names.size(); ++k) {
      writers[k]->startStop();
      const auto progress = [&](double f) {
        if (on_progress) on_progress((static_cast<double>(in * names.size() + k) + f) * share);
      };
      const io::ImportReport r =
          readTopic(s, TopicSource{in, k, names[k]}, *writers[k], record, out, progress);
      result.read[k].scans += r.scans;
      if (r.short_stops) result.short_stops.push_back(names[k] + " in " + record.name);
      if (result.read[k].sensor_name.empty()) result.read[k].sensor_name = r.sensor_name;
      for (const auto& note : r.notes)
        if (std::find(result.notes.begin(), result.notes.end(), note) == result.notes.end())
          result.notes.push_back(note);
    }
    result.meta.inputs.push_back(record);
  }
  const bool known = s.base.bag_pose.kind != io::BagPoseConfig::Kind::none;
  if (known && out.missing_pose)
    throw DataError(s.base.out.string(), "--pose", "some scans have no pose of the vehicle frame",
                    "name the vehicle frame with --vehicle-frame, or import without --pose");
  result.meta.pose_source =
      !known ? "none"
             : (s.base.bag_pose.kind == io::BagPoseConfig::Kind::tf ? "tf:" : "odom:") +
                   s.base.bag_pose.name;
  noteMountings(names, result);
  std::vector<io::RigScan>& rows = out.rows;
  result.stops = assignStops(rows, s.base.bag_pose, known);
  // scans.csv: by sensor, then in the order written.
  std::stable_sort(rows.begin(), rows.end(), [&](const io::RigScan& a, const io::RigScan& b) {
    return std::find(names.begin(), names.end(), a.sensor) <
           std::find(names.begin(), names.end(), b.sensor);
  });
  for (std::size_t k = 0; k < names.size(); ++k)
    result.written.push_back(writers[k]->commit(result.read[k].sensor_name));
  io::writeRigMeta(staged.path() / "rig.json", result.meta);
  io::writeRigScans(staged.path() / "scans.csv", rows);
  staged.commit();
  return result;
}

}  // namespace lidarcal::pipeline
