// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Where the candidates' fits start: the path terms (zero-angle offset, step length) from what the
// baseline's refined path shows, the baseline again from a candidate's solution. Internal to the
// diagnosis library.

#include <utility>
#include <vector>

#include "common/pose2.hpp"
#include "diagnosis/sequence/refits.hpp"

namespace lidarcal::diagnosis::sequence {

/// Centroid (x, y) of a path's positions, metres.
std::pair<double, double> pathCentroid(const std::vector<Pose2>& path);

/// Sum of squared distances of the commanded positions from their centroid, m^2.
double pathSpread(const std::vector<Pose2>& path);

/// Turns a start's world (poses and centres) by `turn` about the commanded path's centroid and
/// gives the beams the opposite turn (the zero-angle offset).
void turnStart(JointInit& start, double turn, const std::vector<Pose2>& path);

/// What the odometry steps of a fit under the motion prior show: the angle phi the fitted steps
/// turn by against the commanded ones in the frame of each scan, and the factor 1 + s they
/// stretch by beyond the fit's odometry scale (each step weighted by its information on them,
/// (length / sd)^2). A lidar yawed by a on the robot gives phi = -a in a fit without the offset.
std::pair<double, double> stepTurnAndStretch(const LandmarkObservations& obs,
                                             const JointResult& fit, const JointConfig& cfg);

}  // namespace lidarcal::diagnosis::sequence
