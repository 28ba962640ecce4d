// SPDX-License-Identifier: BSD-3-Clause
#include "io/landmarks_to_observations.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "common/errors.hpp"
#include "io/landmarks_csv.hpp"

namespace lidarcal::io {

std::vector<Observation> observationsFromLandmarksCsv(const std::filesystem::path& file,
                                                      RangeReference reference) {
  std::vector<Observation> out;
  for (const LandmarkRow& row : readLandmarksCsv(file)) {
    if (row.stop > static_cast<std::size_t>(std::numeric_limits<int>::max()))
      throw InputError(file.string(), "column stop",
                       "stop " + std::to_string(row.stop) + " is too large",
                       "landmarks.csv is written by `lidarcal detect` (docs/FORMAT.md)");
    Observation o;
    o.stop = static_cast<int>(row.stop);
    o.sensor = 0;
    o.landmark = row.landmark;
    o.bearing_rad = row.bearing_rad;
    o.range_m = reference == RangeReference::surface ? row.range_m - row.radius_m : row.range_m;
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
