// SPDX-License-Identifier: BSD-3-Clause
// lidarcal import [--from rosbag1|rosbag2|carmen|ydlidar|csv] INPUT --out SEQ [options]
// Streams a recording into a PCD scan sequence (docs/FORMAT.md, "Importing recordings").

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "io/detect_format.hpp"
#include "io/import_rosbag.hpp"
#include "pipeline/commands/cmd_rig.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/words.hpp"
#include "pipeline/stages/import.hpp"

namespace lidarcal::pipeline {
namespace {

struct ImportOptions {
  std::string from;
  std::vector<std::string> inputs;
  bool stop_per_input = false;
  std::string out;
  std::string topic;
  bool list_topics = false;
  std::size_t every = 1;
  std::size_t max_scans = 0;
  bool overwrite = false;
  bool ascii = false;
  std::string pose = "corrected";
  double range_min_m = 0.0;
  double range_max_m = 0.0;
  std::string sensor_name;
  double still_m = io::BagPoseConfig{}.still_m;
  double still_deg = rad2deg(io::BagPoseConfig{}.still_rad);
  std::string sensor_names;            // rig: one per topic
  std::string vehicle_frame = "auto";  // rig: the frame the mountings are in
  std::string wheels;                  // TOPIC:LEFT,RIGHT
};

/// rosbag1/rosbag2 --pose odom:TOPIC | tf:FRAME.
io::BagPoseConfig bagPose(const ImportOptions& o, const CLI::App& sub) {
  io::BagPoseConfig p = parseBagPose(o.pose);
  if (!(o.still_m >= 0.0))
    throw InputError("", "--still-m", "must be >= 0", "give a distance in metres");
  if (!(o.still_deg >= 0.0))
    throw InputError("", "--still-deg", "must be >= 0", "give an angle in degrees");
  if (sub.count("--still-m")) p.still_m = o.still_m;
  if (sub.count("--still-deg")) p.still_rad = deg2rad(o.still_deg);
  return p;
}

/// --from, or the format every input's content shows (they must agree).
ImportFormat inputFormat(const ImportOptions& o) {
  if (!o.from.empty()) return parseImportFormat(o.from);
  const ImportFormat first = detectImportFormat(o.inputs.front());
  for (const auto& input : o.inputs)
    if (const ImportFormat f = detectImportFormat(input); f != first)
      throw InputError(input, "",
                       std::string("reads as ") + toString(f) + " but " + o.inputs.front() +
                           " as " + toString(first),
                       "import recordings of one format together (or give --from)");
  return first;
}

void printTopics(const ImportOptions& o) {
  const std::vector<io::BagTopic> topics = listTopics(inputFormat(o), o.inputs.front());
  std::printf("| topic | type | messages |\n|---|---|---|\n");
  for (const io::BagTopic& t : topics)
    std::printf("| %s | %s | %zu |\n", t.topic.c_str(), t.datatype.c_str(), t.messages);
}

/// Bytes of an input for the progress display (a ROS 2 bag directory: its files).
std::uintmax_t inputBytes(const std::filesystem::path& input) {
  std::error_code ec;
  if (!std::filesystem::is_directory(input, ec)) {
    const auto size = std::filesystem::file_size(input, ec);
    return ec ? 0 : size;
  }
  std::uintmax_t bytes = 0;
  for (const auto& e : std::filesystem::directory_iterator(input, ec))
    if (e.is_regular_file(ec)) bytes += e.file_size(ec);
  return bytes;
}

/// --pose (a bag's odometry topic or tf frame, or a CARMEN log's pose) and the stillness
/// options that need it.
void applyPoseOptions(const ImportOptions& o, const CLI::App& sub, ImportSettings& s) {
  if (sub.count("--pose") && isBag(s.format)) {
    s.bag_pose = bagPose(o, sub);
  } else if (sub.count("--pose")) {
    if (s.format != ImportFormat::carmen)
      throw InputError("", "--pose", "applies to --from carmen, rosbag1 and rosbag2 only",
                       "drop --pose");
    if (o.pose != "corrected" && o.pose != "odometry")
      throw InputError("", "--pose " + o.pose, "for a CARMEN log, --pose is corrected or odometry",
                       "e.g. --pose odometry");
    s.carmen_pose = o.pose == "odometry" ? io::CarmenPose::odometry : io::CarmenPose::corrected;
  }
  if ((sub.count("--still-m") || sub.count("--still-deg")) &&
      s.bag_pose.kind == io::BagPoseConfig::Kind::none)
    throw InputError("", "--still-m/--still-deg",
                     "apply to a ROS bag with --pose odom:TOPIC or tf:FRAME only",
                     "drop them, or give --pose");
}

/// What an import wrote, in a few lines.
void printImportSummary(const ImportOptions& o, const ImportResult& r, ImportFormat format) {
  const auto& w = r.written;
  const std::string from =
      o.inputs.size() == 1 ? o.inputs.front() : std::to_string(o.inputs.size()) + " recordings";
  std::printf("imported %zu of %s from %s (%s) into %s\n", w.written,
              plural(r.read.scans, "scan").c_str(), from.c_str(), toString(format), w.out.c_str());
  if (o.stop_per_input)
    std::printf("  one stop per recording (%zu; sequence.json stop_starts)\n", o.inputs.size());
  if (w.min_beams == w.max_beams)
    std::printf("  beams per scan: %zu\n", w.max_beams);
  else
    std::printf("  beams per scan: %zu-%zu (sequence.json has no `beams`)\n", w.min_beams,
                w.max_beams);
  std::printf(
      "  returns: %zu of %zu points; %zu without return in the source, %zu outside the range "
      "limits\n",
      w.returns, w.points, w.no_return, w.outside_limits);
  std::printf("  scans with intensity: %zu\n", w.with_intensity);
  if (!o.wheels.empty())
    std::printf("  wheel angles: %zu of %zu scans (wheel_angles.csv%s)\n", w.with_wheels, w.written,
                w.with_wheels < w.written ? "; the others lie outside the joint states" : "");
  if (r.read.other_records) std::printf("  other records ignored: %zu\n", r.read.other_records);
  if (r.read.stopped_early) std::printf("  stopped after --max-scans %zu\n", o.max_scans);
  for (const auto& note : r.read.notes) std::printf("  %s\n", note.c_str());
}

void runImport(const ImportOptions& o, const CLI::App& sub) {
  if (o.list_topics) return printTopics(o);
  if (o.out.empty())
    throw InputError("", "--out", "is required", "give the sequence directory to create");
  ImportSettings s;
  s.format = inputFormat(o);
  if (o.from.empty() && !quiet())
    std::fprintf(stderr, "import: reading %s as %s (from its content; --from overrides)\n",
                 o.inputs.front().c_str(), toString(s.format));
  s.inputs.assign(o.inputs.begin(), o.inputs.end());
  s.stop_per_input = o.stop_per_input;
  s.out = o.out;
  s.topic = o.topic;
  s.writer.every = o.every;
  s.writer.max_scans = o.max_scans;
  s.writer.overwrite = o.overwrite;
  s.writer.encoding = o.ascii ? io::PcdEncoding::ascii : io::PcdEncoding::binary;
  applyPoseOptions(o, sub, s);
  if (sub.count("--wheels")) {
    if (!isBag(s.format))
      throw InputError("", "--wheels", "applies to --from rosbag1 and rosbag2 only",
                       "write wheel_angles.csv yourself for other recordings (docs/FORMAT.md)");
    s.wheels = io::WheelJoints::parse(o.wheels, "--wheels");
  }
  if (sub.count("--range-min")) s.range_min_m = o.range_min_m;
  if (sub.count("--range-max")) s.range_max_m = o.range_max_m;
  s.sensor_name = o.sensor_name;
  if (const std::vector<std::string> topics = splitList(o.topic);
      topics.size() > 1 || sub.count("--sensor-names")) {
    RigImportSettings rig;  // several topics: a rig sequence
    rig.base = s;
    rig.topics = topics;
    rig.names = splitList(o.sensor_names);
    rig.vehicle_frame = o.vehicle_frame;
    return runRigImport(rig);
  }
  if (sub.count("--vehicle-frame"))
    throw InputError("", "--vehicle-frame", "applies to a rig (several topics) only",
                     "drop it, or list the topics");

  // Progress in KiB of the inputs read (the number of scans is not known before the end).
  std::uintmax_t bytes = 0;
  for (const auto& input : s.inputs) bytes += inputBytes(input);
  const std::size_t kib = std::max<std::size_t>(1, static_cast<std::size_t>(bytes / 1024));
  Progress progress("import (KiB read)", kib);
  const ImportResult r = importRecording(s, [&](double fraction) {
    progress.update(static_cast<std::size_t>(fraction * static_cast<double>(kib)));
  });
  progress.finish();

  printImportSummary(o, r, s.format);
}

}  // namespace

void addImportCommand(CLI::App& app) {
  auto o = std::make_shared<ImportOptions>();
  CLI::App* sub = app.add_subcommand("import",
                                     "Convert a recording (ROS1 bag, ROS 2 bag, CARMEN log, "
                                     "YDLIDAR X4 .dat, CSV; format detected from the content) "
                                     "into a scan sequence, streaming");
  sub->add_option("--from", o->from, "Input format (default: detected from the content)")
      ->check(CLI::IsMember({"rosbag1", "rosbag2", "carmen", "ydlidar", "csv"}));
  sub->add_option("INPUT", o->inputs,
                  "The recording(s) (.bag; ROS 2 bag directory, .mcap or .db3; CARMEN .log or "
                  ".log.gz; .dat; .csv; text inputs "
                  "may be gzip), imported one "
                  "after the other into one sequence")
      ->required();
  sub->add_flag("--stop-per-input", o->stop_per_input,
                "Each recording is one stop, even where their poses are equal (e.g. a static "
                "sensor recorded at "
                "several measured target distances; sequence.json stop_starts, docs/FORMAT.md)");
  sub->add_option("-o,--out", o->out,
                  "Sequence directory to create (scan_NNNNNN.pcd + sequence.json)");
  sub->add_option(
      "--topic", o->topic,
      "rosbag1/rosbag2: the LaserScan topic (sensor_msgs/LaserScan, sensor_msgs/msg/LaserScan; "
      "default: the "
      "bag's only one); several, comma-separated (/scan_front,/scan_back): one rig sequence of the "
      "vehicle's "
      "sensors, with each scan's vehicle pose and stop and each sensor's mounting from /tf_static "
      "(docs/FORMAT.md, \"Several sensors on one vehicle\")");
  sub->add_option("--sensor-names", o->sensor_names,
                  "rosbag1/rosbag2 with several --topic: a short name per topic, in order "
                  "(default: the topics without "
                  "their slash), e.g. front,back");
  sub->add_option("--vehicle-frame", o->vehicle_frame,
                  "rosbag1/rosbag2 with several --topic: the frame the sensors' mountings are read "
                  "in from /tf_static "
                  "(default auto: the frame below the first /tf link above each scan frame, e.g. "
                  "base_footprint)")
      ->capture_default_str();
  sub->add_option("--wheels", o->wheels,
                  "rosbag1/rosbag2: TOPIC:LEFT_JOINT,RIGHT_JOINT of sensor_msgs/JointState; each "
                  "wheel's angle at each scan goes to SEQ/wheel_angles.csv (for odometry-drive)");
  sub->add_flag("--list-topics", o->list_topics, "rosbag1/rosbag2: list the bag's topics and exit");
  sub->add_option("--every", o->every, "Keep every N-th scan")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--max-scans", o->max_scans, "Stop after writing N scans (0 = all)")
      ->capture_default_str();
  sub->add_option(
         "--pose", o->pose,
         "carmen: VIEWPOINT from the laser pose (`corrected`: FLASER x y theta) or the odometry "
         "(`odometry`: FLASER odom_x odom_y odom_theta). rosbag1/rosbag2: `odom:TOPIC` "
         "(nav_msgs/Odometry, composed "
         "with the sensor's mount from /tf_static) or `tf:FIXED_FRAME` (the scan frame's pose "
         "through /tf and "
         "/tf_static), interpolated at each scan's stamp")
      ->capture_default_str();
  sub->add_option("--still-m", o->still_m,
                  "rosbag1/rosbag2 with --pose: poses within this distance (m) of a stop's first "
                  "pose are that pose (the "
                  "scans form one stop)")
      ->capture_default_str();
  sub->add_option("--still-deg", o->still_deg,
                  "rosbag1/rosbag2 with --pose: ... and within this heading change (degrees)")
      ->capture_default_str();
  sub->add_option("--range-min", o->range_min_m,
                  "Readings below this (m) become beams without return (default: per format)");
  sub->add_option("--range-max", o->range_max_m,
                  "Readings above this (m) become beams without return (default: per format)");
  sub->add_option("--sensor-name", o->sensor_name,
                  "sensor_name written to sequence.json (default: from the input)");
  sub->add_flag("--ascii", o->ascii, "Write ASCII PCD instead of binary");
  sub->add_flag("--overwrite", o->overwrite, "Replace SEQ if it exists");
  sub->footer(std::string("ROS1 bag support in this build: ") +
              (io::rosbagSupported() ? "yes" : "no") +
              "; ROS 2 bags (.mcap, .db3, bag directories) are always read. Formats, conventions "
              "and range limits: docs/FORMAT.md.");
  sub->callback([o, sub] { runImport(*o, *sub); });
}

}  // namespace lidarcal::pipeline
