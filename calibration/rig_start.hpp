// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to the rig calibration: where the fit starts. A designed mounting a few degrees off
// puts a pole metres away a radius or more off for the other sensors, and rays that miss a
// circle tell little about it, so the fit starts from the poles as the reference sensor sees
// them and from each other sensor's mounting aligned to the poles it shares with the sensors
// already placed (least squares over its sightings' centres, at the recorded vehicle poses).

#include <cstddef>
#include <map>
#include <vector>

#include <Eigen/Core>

#include "common/rig.hpp"

namespace lidarcal::calibration::rig {

/// A pole's centre as one sighting shows it, in the sensor's frame: the middle beam's reading
/// plus the radius along that beam (the beam angle signed by `flip` into the vehicle's sense).
Eigen::Vector2d sightingCentre(const RigSighting& s, double flip, double radius_m);

/// Starting mountings (in: the priors; out: aligned) and pole centres (frame of the vehicle's
/// poses). Sensors that share no pole with the placed ones keep their prior.
void startingGeometry(const RigObservations& obs, const std::vector<double>& flips, double radius_m,
                      std::size_t reference, std::vector<Pose2>& mountings,
                      std::map<int, Eigen::Vector2d>& poles);

}  // namespace lidarcal::calibration::rig
