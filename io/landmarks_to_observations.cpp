// SPDX-License-Identifier: BSD-3-Clause
#include "io/landmarks_to_observations.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "common/errors.hpp"
#include "io/csv_row.hpp"

namespace lidarcal::io {

std::vector<Observation> observationsFromLandmarksCsv(const std::filesystem::path& file,
                                                      RangeReference reference) {
  CsvReader csv(file, "landmarks.csv is written by `lidarcal detect` (docs/FORMAT.md)");
  const std::vector<std::string> header = csv.readHeader();
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  for (const char* needed : {"stop", "landmark", "bearing_rad", "range_m", "radius_m"})
    if (!column.count(needed))
      throw InputError(file.string(), "line 1",
                       std::string("no column `") + needed + "` in the header",
                       "landmarks.csv is written by `lidarcal detect` (docs/FORMAT.md)");
  std::vector<Observation> out;
  while (csv.next(header.size())) {
    Observation o;
    const long long stop = csv.integer(column["stop"], "stop");
    if (stop < 0 || stop > 100'000'000) csv.fail("stop", "must be a stop index >= 0");
    o.stop = static_cast<int>(stop);
    o.sensor = 0;
    const long long id = csv.integer(column["landmark"], "landmark");
    o.landmark = id > 0 && id <= 100'000'000 ? static_cast<int>(id) : -1;
    o.bearing_rad = csv.number(column["bearing_rad"], "bearing_rad");
    o.range_m = csv.number(column["range_m"], "range_m");
    if (reference == RangeReference::surface) {
      const double radius = csv.number(column["radius_m"], "radius_m");
      if (radius < 0.0) csv.fail("radius_m", "must not be negative");
      o.range_m -= radius;
    }
    out.push_back(o);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Observation& a, const Observation& b) { return a.stop < b.stop; });
  return out;
}

std::vector<OdometryStep> odometryFromStops(const std::vector<Stop>& stops) {
  std::vector<OdometryStep> out;
  for (std::size_t k = 0; k < stops.size(); ++k) {
    OdometryStep s;
    s.stop = static_cast<int>(k);
    if (k > 0) {
      const Pose2& a = stops[k - 1].commanded;
      const Pose2& b = stops[k].commanded;
      a.toSensor(b.x_m, b.y_m, s.dx_m, s.dy_m);
      s.dtheta_rad = wrapAngle(b.yaw_rad - a.yaw_rad);
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace lidarcal::io
