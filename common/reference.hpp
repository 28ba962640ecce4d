#pragma once
// What a user measured by hand (a tape measure, a laser distance meter, a survey) about a
// recorded sequence: the content of REF.json (docs/FORMAT.md, "Reference measurements").
// Plain data: io/ reads it, calibration/ fits the range model against it (seed 004 section 5:
// calibration against known distances), pipeline/ evaluates a model with it.

#include <cstddef>
#include <optional>
#include <vector>

#include "common/pose2.hpp"

namespace lidarcal {

/// What a measured distance ends at.
enum class ReferenceTarget {
  landmark,  ///< the centre of a pole (cylinder) seen at that stop
  wall,      ///< a flat surface: the perpendicular distance from the sensor to its plane
};

/// One measured distance from the sensor origin at one stop.
struct ReferenceDistance {
  std::size_t stop = 0;                      ///< stop index in the sequence (0-based)
  ReferenceTarget target = ReferenceTarget::landmark;  ///< what the distance ends at
  double distance_m = 0.0;                   ///< measured distance, metres (> 0)
  /// Direction of the target in the sensor frame, radians; unset: the target whose measured
  /// range is nearest distance_m.
  std::optional<double> bearing_rad;
  /// Standard deviation of the measurement, metres (a tape read to the millimetre and placed by
  /// hand: a few millimetres). Default 0.002.
  double sigma_m = 0.002;
};

/// A surveyed landmark: its centre in the frame of the sequence's VIEWPOINTs.
struct ReferenceLandmark {
  double x_m = 0.0, y_m = 0.0;         ///< centre, metres
  std::optional<double> radius_m;      ///< radius when measured, metres
};

/// A measured sensor pose at one stop, in the frame of the VIEWPOINTs.
struct ReferenceStop {
  std::size_t stop = 0;  ///< stop index (0-based)
  Pose2 pose;            ///< measured pose (position in metres, heading in radians)
};

/// Everything measured; every part optional.
struct Reference {
  std::vector<ReferenceDistance> distances;
  std::vector<ReferenceLandmark> landmarks;
  std::vector<ReferenceStop> stops;
  bool empty() const { return distances.empty() && landmarks.empty() && stops.empty(); }
};

}  // namespace lidarcal
