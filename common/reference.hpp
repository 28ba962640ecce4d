// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What a user measured by hand (a tape measure, a laser distance meter, a survey) about a
// recorded sequence: the content of REF.json (docs/FORMAT.md, "Reference measurements").
// Plain data: io/ reads it, calibration/ fits the range model against it (Alhashimi et al. 2016
// section 5: calibration against known distances; wall-to-wall spans, calibration/span_fit.hpp),
// pipeline/ evaluates a model with it.

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
  std::size_t stop = 0;                                ///< stop index in the sequence (0-based)
  ReferenceTarget target = ReferenceTarget::landmark;  ///< what the distance ends at
  double distance_m = 0.0;                             ///< measured distance, metres (> 0)
  /// Direction of the target in the sensor frame, radians; unset: the target whose measured
  /// range is nearest distance_m.
  std::optional<double> bearing_rad;
  /// Standard deviation of the measurement, metres (a tape read to the millimetre and placed by
  /// hand: a few millimetres; 0: taken as exact). Default 0.002.
  double sigma_m = 0.002;
};

/// The measured distance between two parallel walls that a stop sees on opposite sides (a laser
/// distance meter held across the room): the sum of the sensor's perpendicular distances to the
/// two walls. Each wall is named by the direction of its normal from the sensor: the direction,
/// in the sensor frame, in which that wall is nearest.
struct ReferenceSpan {
  std::size_t stop = 0;        ///< stop index in the sequence (0-based)
  double bearing_a_rad = 0.0;  ///< approximate normal direction of one wall, sensor frame, radians
  double bearing_b_rad = 0.0;  ///< approximate normal direction of the other wall, radians
  double distance_m = 0.0;     ///< measured wall-to-wall distance, metres (> 0)
  /// Standard deviation of the measurement, metres (a laser distance meter: about 2 mm). Default
  /// 0.002.
  double sigma_m = 0.002;
};

/// A surveyed landmark: its centre in the frame of the sequence's VIEWPOINTs.
struct ReferenceLandmark {
  double x_m = 0.0, y_m = 0.0;     ///< centre, metres
  std::optional<double> radius_m;  ///< radius when measured, metres
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
  std::vector<ReferenceSpan> spans;
  bool empty() const {
    return distances.empty() && landmarks.empty() && stops.empty() && spans.empty();
  }
};

}  // namespace lidarcal
