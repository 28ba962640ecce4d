// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/refusals.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "calibration/inversion.hpp"
#include "common/plural.hpp"

namespace lidarcal::calibration {
namespace {

/// A length for a message: "1.23 m".
std::string metres(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f m", v);
  return buf;
}

/// The refusal when no landmark could be triangulated: the first three reasons, what to record.
void refuseNoUsableLandmark(CalibrationModel& m, const std::vector<LandmarkEstimate>& tri) {
  m.status.code = StatusCode::no_usable_landmark;
  m.status.message = tri.empty() ? "no landmark was observed (check what lidarcal detect finds)"
                                 : "no landmark could be triangulated";
  for (std::size_t i = 0; i < tri.size() && i < 3; ++i)
    m.status.message += "; landmark " + std::to_string(tri[i].id) + ": " + m.landmarks[i].status;
  if (tri.size() > 3) m.status.message += "; and " + std::to_string(tri.size() - 3) + " more";
  m.status.message +=
      ". Record 3 or more stops along a straight line past 3 or more poles (cylinders 5-30 cm "
      "across, "
      "free-standing, 0.5-4 m away), give their radius with --radius if they are thinner, or give "
      "measured "
      "distances with --reference";
}

}  // namespace

double pathExtent(const std::vector<Pose2>& poses) {
  if (poses.empty()) return 0.0;
  double min_x = poses.front().x_m, max_x = min_x, min_y = poses.front().y_m, max_y = min_y;
  for (const auto& p : poses) {
    min_x = std::min(min_x, p.x_m);
    max_x = std::max(max_x, p.x_m);
    min_y = std::min(min_y, p.y_m);
    max_y = std::max(max_y, p.y_m);
  }
  return std::hypot(max_x - min_x, max_y - min_y);
}

std::optional<std::string> baselineProblem(const std::vector<Pose2>& stops,
                                           const CalibrationConfig& config) {
  const double baseline = pathExtent(stops);
  if (stops.size() < 2 || baseline >= config.min_baseline_m) return std::nullopt;
  return "the " + plural(stops.size(), "stop") + " lie within " + metres(baseline) +
         " of each other (the sensor turned or stood still), so the landmarks cannot be placed "
         "from their bearings: "
         "record stops along a straight line of at least 1 m (a quarter of the distance to the "
         "poles or more), or "
         "give measured distances with --reference (docs/FORMAT.md)";
}

bool refuseUnusableInput(CalibrationModel& m, const LandmarkObservations& obs,
                         const CalibrationConfig& config) {
  // Triangulating from bearings needs the sensor to translate: stops at one place (a sensor
  // turning on the spot, or standing still) give every landmark the same bearing line.
  if (const auto problem = baselineProblem(obs.commanded, config);
      problem && !obs.sightings.empty()) {
    m.status.code = StatusCode::no_baseline;
    m.status.message = *problem;
    return true;
  }
  // The dark-surface noise term fits the noise against the return intensity: nothing to fit without
  // one.
  if (config.method == Method::joint && config.joint.effects.dark_noise && !intensitiesVary(obs)) {
    m.status.code = StatusCode::no_intensity;
    m.status.message =
        "--effects dark_surface fits the noise against the return intensity, and no reading of "
        "these "
        "scans records one (or all record the same value): record with the driver's intensities on "
        "(ROS LaserScan intensities, a PCD intensity field), or leave dark_surface out of "
        "--effects";
    return true;
  }
  return false;
}

bool refuseTriangulation(CalibrationModel& m, const std::vector<LandmarkEstimate>& tri, int usable,
                         double radius_m) {
  if (usable == 0) {
    refuseNoUsableLandmark(m, tri);
    return true;
  }
  if (!(radius_m > 0.0)) {
    m.status.code = StatusCode::no_radius;
    m.status.message = "the landmark radius is unknown and could not be estimated";
    return true;
  }
  return false;
}

bool refuseTooFewPairs(CalibrationModel& m, const LandmarkObservations& obs,
                       const CalibrationConfig& config, const std::vector<LandmarkEstimate>& tri,
                       std::size_t pairs, int usable) {
  if (pairs >= static_cast<std::size_t>(config.max_order) + 3) return false;
  std::size_t read = 0;  // sightings with a finite central reading on a triangulated landmark
  for (const auto& s : obs.sightings)
    for (const auto& l : tri)
      if (l.ok() && l.id == s.landmark && !s.beams.empty() &&
          std::isfinite(s.beams[centralBeam(s)].range_m))
        ++read;
  m.status.code = StatusCode::too_few_observations;
  m.status.message = "only " + plural(pairs, "landmark-stop distance") + " from " +
                     plural(static_cast<std::size_t>(usable), "triangulated landmark") +
                     " (at least " + std::to_string(config.max_order + 3) + " needed)";
  if (read > 0 && pairs == 0)
    m.status.message += ": none of the " + plural(read, "reading") +
                        " meets its triangulated landmark in front of the sensor, so the "
                        "bearing-only positions are wrong "
                        "(a path of " +
                        metres(pathExtent(obs.commanded)) + " is short for landmarks this far)";
  m.status.message +=
      ": record more stops along a longer straight line past 3 or more poles, or give measured "
      "distances with "
      "--reference";
  return true;
}

bool refuseJoint(CalibrationModel& m, const JointResult& j, const LandmarkObservations& obs,
                 int usable, double baseline) {
  if (!j.ok()) {
    m.status.code = StatusCode::joint_failed;
    m.status.message =
        j.status.message + " (" + plural(static_cast<std::size_t>(usable), "landmark") +
        " triangulated over a path of " + metres(baseline) +
        ": the beams that saw them do not meet the triangulated circles). Record stops along "
        "a longer straight line past 3 or more poles, give the pole radius (--radius), or use "
        "--method "
        "closed-form";
    return true;
  }
  const auto [near, far] = std::minmax_element(j.distances_m.begin(), j.distances_m.end());
  if (far == j.distances_m.end()) return false;
  const std::string advice =
      " (too little geometry to pin it down: record more stops along a longer line past more "
      "poles, or use --method "
      "closed-form)";
  if (!(*near > 0.0)) {
    // Collapsed: the landmarks moved onto the stops, and a bias of any slope explains readings at
    // zero distance (seen on a YDLIDAR recording of four poles: slope -776).
    m.status.code = StatusCode::joint_failed;
    m.status.message =
        "the joint refinement collapsed: it places a landmark at a stop (a beam distance of " +
        std::to_string(*near) + " m)" + advice;
    return true;
  }
  if (!isMonotone(j.model.bias, *near, *far)) {
    m.status.code = StatusCode::joint_failed;
    m.status.message = "the joint refinement's bias falls with distance somewhere in " +
                       std::to_string(*near) + "-" + std::to_string(*far) +
                       " m, where it saw the landmarks, so no reading there has one distance" +
                       advice;
    return true;
  }
  if (!(obs.range_max_m < 1e8)) return false;
  const double limit = 1.5 * obs.range_max_m + 0.5;
  if (*far <= limit) return false;
  m.status.code = StatusCode::joint_failed;
  m.status.message = "the joint refinement ran away: it places a landmark " + std::to_string(*far) +
                     " m from a stop, beyond the sensor's range limit of " +
                     std::to_string(obs.range_max_m) + " m" + advice;
  return true;
}

}  // namespace lidarcal::calibration
