// SPDX-License-Identifier: BSD-3-Clause
#include "io/import_carmen.hpp"

#include <cmath>
#include <limits>
#include <string_view>

#include "common/errors.hpp"
#include "io/line_reader.hpp"
#include "io/text_fields.hpp"

namespace lidarcal::io {
namespace {

constexpr const char* kFormatRemedy = "see docs/FORMAT.md (CARMEN logs); fix or delete the line";
constexpr std::size_t kMaxBeams = 100000;  // refuse absurd counts before allocating

/// Field of view of a FLASER scan with n beams, radians. FLASER lines carry no angles; CARMEN
/// infers them from the beam count (SICK LMS modes): 181/361 beams span 180 deg, 180/360 beams
/// span 179/179.5 deg (the last beam of the sweep is dropped), 401/400 beams 100/99.75 deg,
/// anything else is taken as 180 deg. Beams are equally spaced from -fov/2, counter-clockwise.
double flaserFov_rad(std::size_t n) {
  switch (n) {
    case 180:
      return deg2rad(179.0);
    case 360:
      return deg2rad(179.5);
    case 401:
      return deg2rad(100.0);
    case 400:
      return deg2rad(99.75);
    default:
      return kPi;
  }
}

class LineParser {
 public:
  LineParser(const LineReader& reader, std::string_view keyword,
             const std::vector<std::string_view>& fields)
      : reader_(reader), keyword_(keyword), fields_(fields) {}

  std::string item() const {
    return "line " + std::to_string(reader_.lineNumber()) + " (" + std::string(keyword_) + ")";
  }

  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(reader_.file().string(), item(), problem, kFormatRemedy);
  }

  double number(std::size_t i, const char* what) const {
    if (i >= fields_.size())
      fail("ends before its " + std::string(what) + " (value " + std::to_string(i) + ")");
    double v = 0.0;
    if (!parseNumber(fields_[i], v))
      fail(std::string(what) + " (value " + std::to_string(i) + ") is '" + std::string(fields_[i]) +
           "', not a number");
    return v;
  }

  /// Reads x y theta starting at field i.
  Pose2 pose(std::size_t i) const {
    const double x = number(i, "x"), y = number(i + 1, "y"), theta = number(i + 2, "theta");
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(theta))
      fail("the pose is not finite");
    return Pose2{x, y, wrapAngle(theta)};
  }

  std::size_t count(std::size_t i, const char* what) const {
    const double v = number(i, what);
    if (!(v >= 0.0) || v != std::floor(v) || v > static_cast<double>(kMaxBeams))
      fail(std::string(what) + " is '" + std::string(fields_[i]) +
           "', expected a whole number from 0 to " + std::to_string(kMaxBeams));
    return static_cast<std::size_t>(v);
  }

  /// `layout` names the values expected (only composed into the message on failure).
  void expectValues(std::size_t expected, const char* layout) const {
    const std::size_t got = fields_.size() - 1;  // values after the keyword
    if (got != expected)
      fail("has " + std::to_string(got) + " values after " + std::string(keyword_) + ", expected " +
           std::to_string(expected) + " (" + layout +
           "): the line is cut short or merged with another");
  }

  void ranges(std::size_t first, std::size_t n, std::vector<float>& out) const {
    out.resize(n);
    for (std::size_t k = 0; k < n; ++k)
      out[k] = static_cast<float>(number(first + k, "range reading"));
  }

 private:
  const LineReader& reader_;
  std::string_view keyword_;
  const std::vector<std::string_view>& fields_;
};

void parseFlaser(const LineParser& p, const CarmenConfig& config, RawScan& scan) {
  const std::size_t n = p.count(1, "beam count");
  p.expectValues(n + 10,
                 "n + 10: the beam count n, n ranges, x y theta odom_x odom_y odom_theta, "
                 "ipc_timestamp ipc_hostname logger_timestamp");
  p.ranges(2, n, scan.ranges_m);
  scan.pose = p.pose(2 + n + (config.pose == CarmenPose::corrected ? 0 : 3));
  scan.stamp_s = p.number(2 + n + 6, "ipc_timestamp");
  const double fov = flaserFov_rad(n);
  const double step = n > 1 ? fov / static_cast<double>(n - 1) : 0.0;
  scan.angles_rad.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    scan.angles_rad[i] = -0.5 * fov + static_cast<double>(i) * step;
  scan.intensities.clear();
  scan.range_max_m = config.range_max_m.value_or(kFlaserRangeMax_m);
}

void parseRobotlaser(const LineParser& p, const CarmenConfig& config, RawScan& scan) {
  const double start = p.number(2, "start_angle");
  const double resolution = p.number(4, "angular_resolution");
  const double max_range = p.number(5, "maximum_range");
  const std::size_t n = p.count(8, "num_readings");
  const std::size_t m = p.count(9 + n, "num_remissions");
  p.expectValues(
      n + m + 23,
      "n + m + 23: 7 laser settings, the beam count n, n ranges, the remission count m, "
      "m remissions, laser pose, robot pose, 5 motion values, timestamp hostname logger_timestamp");
  p.ranges(9, n, scan.ranges_m);
  scan.intensities.clear();
  if (m == n && n > 0) p.ranges(10 + n, m, scan.intensities);
  const std::size_t poses = 10 + n + m;
  scan.pose = p.pose(poses + (config.pose == CarmenPose::corrected ? 0 : 3));
  scan.stamp_s = p.number(poses + 11, "timestamp");
  scan.angles_rad.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    scan.angles_rad[i] = start + static_cast<double>(i) * resolution;
  scan.range_max_m = config.range_max_m.value_or(max_range);
  if (!(scan.range_max_m > 0.0)) p.fail("maximum_range must be positive");
}

}  // namespace

void CarmenConfig::validate() const {
  checkRangeLimits(range_min_m, range_max_m.value_or(std::numeric_limits<double>::infinity()));
}

ImportReport readCarmenLog(const std::filesystem::path& log, const CarmenConfig& config,
                           const ScanCallback& on_scan) {
  config.validate();
  LineReader reader(log);
  ImportReport report;
  std::string line;
  std::vector<std::string_view> fields;
  std::string kind;  // FLASER or ROBOTLASER1, fixed by the first laser line
  RawScan scan;
  scan.range_min_m = config.range_min_m;
  while (reader.next(line)) {
    splitWhitespace(line, fields);
    if (fields.empty() || fields[0].front() == '#') continue;
    const std::string_view keyword = fields[0];
    if (keyword != "FLASER" && keyword != "ROBOTLASER1") {
      ++report.other_records;
      continue;
    }
    if (kind.empty()) kind = keyword;
    if (keyword != kind) {
      ++report.other_records;
      continue;
    }
    const LineParser parser(reader, keyword, fields);
    if (keyword == "FLASER")
      parseFlaser(parser, config, scan);
    else
      parseRobotlaser(parser, config, scan);
    scan.source_index = report.scans++;
    scan.progress = reader.progress();
    if (!on_scan(scan)) {
      report.stopped_early = true;
      break;
    }
  }
  if (kind.empty())
    throw InputError(log.string(), "",
                     "no FLASER or ROBOTLASER1 line: not a CARMEN laser log (" +
                         std::to_string(reader.lineNumber()) + " lines read)",
                     "check --from and the file; see docs/FORMAT.md for the CARMEN lines read");
  report.sensor_name = "CARMEN front laser (" + kind + ")";
  report.notes.push_back(
      std::string("VIEWPOINT = ") +
      (config.pose == CarmenPose::corrected
           ? (kind == "FLASER" ? "FLASER x y theta" : "ROBOTLASER1 laser pose") +
                 std::string(" (the laser pose; SLAM-corrected in *-corrected logs)")
           : (kind == "FLASER" ? "FLASER odom_x odom_y odom_theta" : "ROBOTLASER1 robot pose") +
                 std::string(" (odometry)")));
  return report;
}

}  // namespace lidarcal::io
