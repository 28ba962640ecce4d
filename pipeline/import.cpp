#include "pipeline/import.hpp"

#include <limits>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/import_csv.hpp"
#include "io/import_rosbag.hpp"
#include "io/import_ydlidar.hpp"

namespace lidarcal::pipeline {

ImportFormat parseImportFormat(const std::string& name) {
  if (name == "rosbag1") return ImportFormat::rosbag1;
  if (name == "carmen") return ImportFormat::carmen;
  if (name == "ydlidar") return ImportFormat::ydlidar;
  if (name == "csv") return ImportFormat::csv;
  throw InputError("", "--from", "unknown input format '" + name + "'", "use rosbag1, carmen, ydlidar or csv");
}

const char* toString(ImportFormat format) {
  switch (format) {
    case ImportFormat::rosbag1: return "rosbag1";
    case ImportFormat::carmen: return "carmen";
    case ImportFormat::ydlidar: return "ydlidar";
    case ImportFormat::csv: return "csv";
  }
  return "?";
}

ImportResult importRecording(const ImportSettings& s, const std::function<void(double)>& on_progress) {
  if (s.format != ImportFormat::rosbag1 && !s.topic.empty())
    throw InputError("", "--topic", "applies to --from rosbag1 only", "drop --topic");
  if (s.format == ImportFormat::rosbag1) io::requireRosbagSupport(s.input);
  io::checkOutsideInput(s.input, s.out);
  io::SequenceWriter writer(s.out, s.writer);
  const io::ScanCallback on_scan = [&](const io::RawScan& scan) {
    const bool more = writer.add(scan);
    if (on_progress) on_progress(scan.progress);
    return more;
  };
  const double inf = std::numeric_limits<double>::infinity();
  ImportResult result;
  switch (s.format) {
    case ImportFormat::rosbag1: {
      io::RosbagConfig c;
      c.topic = s.topic;
      c.range_min_m = s.range_min_m;
      c.range_max_m = s.range_max_m;
      result.read = io::readRosbag(s.input, c, on_scan);
      break;
    }
    case ImportFormat::carmen: {
      io::CarmenConfig c;
      c.pose = s.carmen_pose;
      c.range_min_m = s.range_min_m.value_or(c.range_min_m);
      c.range_max_m = s.range_max_m;
      result.read = io::readCarmenLog(s.input, c, on_scan);
      break;
    }
    case ImportFormat::ydlidar: {
      io::YdlidarConfig c;
      c.range_min_m = s.range_min_m.value_or(c.range_min_m);
      c.range_max_m = s.range_max_m.value_or(c.range_max_m);
      result.read = io::readYdlidarDat(s.input, c, on_scan);
      break;
    }
    case ImportFormat::csv: {
      io::CsvConfig c;
      c.range_min_m = s.range_min_m.value_or(0.0);
      c.range_max_m = s.range_max_m.value_or(inf);
      result.read = io::readCsvScans(s.input, c, on_scan);
      break;
    }
  }
  result.written = writer.commit(s.sensor_name.empty() ? result.read.sensor_name : s.sensor_name);
  return result;
}

}  // namespace lidarcal::pipeline
