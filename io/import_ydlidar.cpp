// SPDX-License-Identifier: BSD-3-Clause
#include "io/import_ydlidar.hpp"

#include <cmath>
#include <string_view>

#include "common/errors.hpp"
#include "io/line_reader.hpp"
#include "io/text_fields.hpp"

namespace lidarcal::io {

void YdlidarConfig::validate() const {
  if (!(distance_unit_m > 0.0) || !std::isfinite(distance_unit_m))
    throw InputError("", "distance unit", "must be a positive number of metres",
                     "use 0.001 for millimetres");
  if (!std::isfinite(dtheta_unit_rad) || dtheta_unit_rad == 0.0)
    throw InputError("", "dtheta unit", "must be a nonzero number of radians",
                     "use pi/180 for degrees");
  checkRangeLimits(range_min_m, range_max_m);
}

Pose2 integrateOdometry(const Pose2& previous, double distance_m, double dtheta_rad) {
  const double heading = previous.yaw_rad + 0.5 * dtheta_rad;
  return Pose2{previous.x_m + distance_m * std::cos(heading),
               previous.y_m + distance_m * std::sin(heading),
               wrapAngle(previous.yaw_rad + dtheta_rad)};
}

ImportReport readYdlidarDat(const std::filesystem::path& dat, const YdlidarConfig& config,
                            const ScanCallback& on_scan) {
  config.validate();
  LineReader reader(dat);
  ImportReport report;
  std::string line;
  std::vector<std::string_view> fields;
  RawScan scan;
  scan.range_min_m = config.range_min_m;
  scan.range_max_m = config.range_max_m;
  double time_s = 0.0;
  const auto fail = [&](const std::string& problem) {
    throw InputError(dat.string(), "line " + std::to_string(reader.lineNumber()), problem,
                     "see docs/FORMAT.md (YDLIDAR X4 dataset); fix or delete the line");
  };
  while (reader.next(line)) {
    splitCommas(line, fields);
    if (fields.empty()) continue;
    if (fields.size() < 4)
      fail("has " + std::to_string(fields.size()) +
           " values, expected distance, dtheta, dt and at least one range");
    double v[3];
    static const char* const kNames[3] = {"distance", "dtheta", "dt"};
    for (int k = 0; k < 3; ++k)
      if (!parseNumber(fields[static_cast<std::size_t>(k)], v[k]) || !std::isfinite(v[k]))
        fail(std::string(kNames[k]) + " is '" + std::string(fields[static_cast<std::size_t>(k)]) +
             "', not a finite number");
    const std::size_t n = fields.size() - 3;
    scan.ranges_m.resize(n);
    scan.angles_rad.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      double r = 0.0;
      if (!parseNumber(fields[3 + i], r))
        fail("range " + std::to_string(i) + " is '" + std::string(fields[3 + i]) +
             "', not a number");
      scan.ranges_m[i] = static_cast<float>(r);
      scan.angles_rad[i] =
          config.first_beam_rad + 2.0 * kPi * static_cast<double>(i) / static_cast<double>(n);
    }
    if (report.scans == 0) {
      scan.pose = Pose2{};
      report.notes.push_back("line 1: odometry change before the recording (distance " +
                             std::to_string(v[0]) + ", dtheta " + std::to_string(v[1]) + ", dt " +
                             std::to_string(v[2]) + " s) not applied; scan 0 is the origin");
    } else {
      scan.pose = integrateOdometry(scan.pose, v[0] * config.distance_unit_m,
                                    v[1] * config.dtheta_unit_rad);
      time_s += v[2];
    }
    scan.stamp_s = time_s;
    scan.source_index = report.scans++;
    scan.progress = reader.progress();
    if (!on_scan(scan)) {
      report.stopped_early = true;
      break;
    }
  }
  if (report.scans == 0)
    throw InputError(dat.string(), "", "holds no scan line",
                     "check the file; see docs/FORMAT.md (YDLIDAR X4 dataset)");
  report.sensor_name = "YDLIDAR X4";
  report.notes.push_back(
      "VIEWPOINT = odometry integrated from the distance and dtheta columns (line 2 on)");
  return report;
}

}  // namespace lidarcal::io
