// SPDX-License-Identifier: BSD-3-Clause
#include "pipeline/stages/import.hpp"

#include <algorithm>
#include <limits>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/detect_format.hpp"
#include "io/import_csv.hpp"
#include "io/import_rosbag.hpp"
#include "io/import_rosbag2.hpp"
#include "io/import_ydlidar.hpp"

namespace lidarcal::pipeline {

ImportFormat parseImportFormat(const std::string& name) {
  if (name == "rosbag1") return ImportFormat::rosbag1;
  if (name == "rosbag2") return ImportFormat::rosbag2;
  if (name == "carmen") return ImportFormat::carmen;
  if (name == "ydlidar") return ImportFormat::ydlidar;
  if (name == "csv") return ImportFormat::csv;
  throw InputError("", "--from", "unknown input format '" + name + "'",
                   "use rosbag1, rosbag2, carmen, ydlidar or csv");
}

const char* toString(ImportFormat format) {
  switch (format) {
    case ImportFormat::rosbag1:
      return "rosbag1";
    case ImportFormat::rosbag2:
      return "rosbag2";
    case ImportFormat::carmen:
      return "carmen";
    case ImportFormat::ydlidar:
      return "ydlidar";
    case ImportFormat::csv:
      return "csv";
  }
  return "?";
}

io::ImportReport readRecording(const ImportSettings& s, const std::filesystem::path& input,
                               const io::ScanCallback& on_scan) {
  const double inf = std::numeric_limits<double>::infinity();
  switch (s.format) {
    case ImportFormat::rosbag1:
    case ImportFormat::rosbag2: {
      io::RosbagConfig c;
      c.topic = s.topic;
      c.range_min_m = s.range_min_m;
      c.range_max_m = s.range_max_m;
      c.pose = s.bag_pose;
      c.wheels = s.wheels;
      return s.format == ImportFormat::rosbag1 ? io::readRosbag(input, c, on_scan)
                                               : io::readRosbag2(input, c, on_scan);
    }
    case ImportFormat::carmen: {
      io::CarmenConfig c;
      c.pose = s.carmen_pose;
      c.range_min_m = s.range_min_m.value_or(c.range_min_m);
      c.range_max_m = s.range_max_m;
      return io::readCarmenLog(input, c, on_scan);
    }
    case ImportFormat::ydlidar: {
      io::YdlidarConfig c;
      c.range_min_m = s.range_min_m.value_or(c.range_min_m);
      c.range_max_m = s.range_max_m.value_or(c.range_max_m);
      return io::readYdlidarDat(input, c, on_scan);
    }
    case ImportFormat::csv: {
      io::CsvConfig c;
      c.range_min_m = s.range_min_m.value_or(0.0);
      c.range_max_m = s.range_max_m.value_or(inf);
      return io::readCsvScans(input, c, on_scan);
    }
  }
  return {};
}

io::BagPoseConfig parseBagPose(const std::string& spec) {
  io::BagPoseConfig p;
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  if (colon == std::string::npos || (kind != "odom" && kind != "tf") || colon + 1 == spec.size())
    throw InputError("", "--pose " + spec,
                     "for a ROS bag, --pose is odom:TOPIC (nav_msgs/Odometry) or tf:FIXED_FRAME",
                     "e.g. --pose odom:/odom or --pose tf:map");
  p.kind = kind == "odom" ? io::BagPoseConfig::Kind::odom : io::BagPoseConfig::Kind::tf;
  p.name = spec.substr(colon + 1);
  if (kind == "tf" && p.name.front() == '/') p.name.erase(0, 1);  // tf frames have no leading slash
  return p;
}

ImportFormat detectImportFormat(const std::string& input) {
  const io::DetectedFormat d = io::detectRecordingFormat(input);
  switch (d.kind) {
    case io::RecordingKind::rosbag1:
      return ImportFormat::rosbag1;
    case io::RecordingKind::mcap:
    case io::RecordingKind::rosbag2:
      return ImportFormat::rosbag2;
    case io::RecordingKind::carmen:
      return ImportFormat::carmen;
    case io::RecordingKind::ydlidar:
      return ImportFormat::ydlidar;
    case io::RecordingKind::csv:
      return ImportFormat::csv;
    case io::RecordingKind::unknown:
      break;
  }
  throw InputError(
      input, "",
      std::string("cannot tell the recording's format from its content") +
          (d.gzip ? " (gzip-compressed)" : "") +
          ": not a ROS1 or ROS 2 bag, a CARMEN log, a YDLIDAR X4 .dat or a CSV with a header",
      "name the format with --from rosbag1|rosbag2|carmen|ydlidar|csv (docs/FORMAT.md)");
}

bool isBag(ImportFormat format) {
  return format == ImportFormat::rosbag1 || format == ImportFormat::rosbag2;
}

std::vector<io::BagTopic> listTopics(ImportFormat format, const std::filesystem::path& bag) {
  if (format == ImportFormat::rosbag2) return io::listRosbag2Topics(bag);
  if (format == ImportFormat::rosbag1) return io::listBagTopics(bag);
  throw InputError("", "--list-topics", "applies to --from rosbag1 and rosbag2 only",
                   "drop --list-topics");
}

ImportResult importRecording(const ImportSettings& s,
                             const std::function<void(double)>& on_progress) {
  if (s.inputs.empty())
    throw InputError("", "INPUT", "no recording given", "name one or more recordings to import");
  if (!isBag(s.format) && !s.topic.empty())
    throw InputError("", "--topic", "applies to --from rosbag1 and rosbag2 only", "drop --topic");
  for (const auto& input : s.inputs) {
    if (s.format == ImportFormat::rosbag1) io::requireRosbagSupport(input);
    io::checkOutsideInput(input, s.out);
  }
  io::SequenceWriter writer(s.out, s.writer);
  ImportResult result;
  const double share = 1.0 / static_cast<double>(s.inputs.size());
  for (std::size_t k = 0; k < s.inputs.size(); ++k) {
    if (s.stop_per_input) writer.startStop();
    bool more = true;
    const io::ScanCallback on_scan = [&](const io::RawScan& scan) {
      more = writer.add(scan);
      if (on_progress) on_progress((static_cast<double>(k) + scan.progress) * share);
      return more;
    };
    const io::ImportReport read = readRecording(s, s.inputs[k], on_scan);
    result.read.scans += read.scans;
    result.read.other_records += read.other_records;
    result.read.stopped_early = read.stopped_early;
    if (result.read.sensor_name.empty()) result.read.sensor_name = read.sensor_name;
    for (const auto& note : read.notes)
      if (std::find(result.read.notes.begin(), result.read.notes.end(), note) ==
          result.read.notes.end())
        result.read.notes.push_back(note);
    if (!more) break;  // --max-scans reached
  }
  result.written = writer.commit(s.sensor_name.empty() ? result.read.sensor_name : s.sensor_name);
  return result;
}

}  // namespace lidarcal::pipeline
