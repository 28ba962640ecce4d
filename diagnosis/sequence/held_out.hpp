// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Held-out log-likelihoods of a sequence: each scored reading under a fit on the other folds,
// and the odometry left out one stop (stop and go) or one step (a continuous recording) at a
// time. Internal to the diagnosis library.

#include <cstddef>
#include <vector>

#include "diagnosis/sequence/refits.hpp"

namespace lidarcal::diagnosis::sequence {

/// Log-likelihood of each held-out reading (test) under a fit on the others (train), aligned
/// with evaluateJoint(test, ...). Stop and go: the reading's own density at the fit (its stop's
/// pose is learnt from the stop's other scans). Under the motion prior each scan is its own stop,
/// its pose learnt from that scan's other landmarks and the odometry around it: the reading is
/// predicted over the pose's uncertainty (heldOutDistance; to first order g^T C g is added to the
/// variance), its noise at the readings' own variance (noiseDofFactor); scored at the fitted pose
/// alone, beams near a pole's edge fall many noise widths off (docs/FINDINGS.md).
/// scans: when given, receives the scan of each reading.
std::vector<double> heldOutLikelihoods(const LandmarkObservations& train,
                                       const LandmarkObservations& test, const JointResult& fit,
                                       const JointConfig& cfg,
                                       std::vector<std::size_t>* scans = nullptr);

/// Held-out log-likelihood of the odometry: for each stop, the commanded position predicted from
/// everything but its own odometry (its readings locate it in the world the other stops fix).
/// Linearised leave-one-out: with H the information of the stop's position from its readings
/// (heading profiled out when the model refines it), the position without its prior is
/// p + H^-1 (p - c) / sigma_s^2 and c is N(that, sigma_s^2 I + H^-1). c is the commanded position
/// (scaled by 1 + s with the odometry scale).
std::vector<double> odometryHeldOut(const LandmarkObservations& obs, const JointResult& fit,
                                    const JointConfig& cfg);

/// Held-out log-likelihood of each odometry step k - 1 -> k of a fit under the motion prior
/// (element k - 1), predicted from everything but itself: linearised leave-one-out with the
/// landmarks held at the fit (leaveOneOutLogDensity), r the step's residual in units of its
/// standard deviations, S = J C J^T its leverage (forEachLocatedStep), plus ln(1 / (sd_x sd_y
/// sd_psi)) for a density in metres and radians. A lidar yawed on the robot leaves the readings as
/// they were (each scan's heading absorbs it) and turns every step: the steps are where a
/// continuous recording shows its path terms. NaN for a step whose two poses the readings do not
/// both locate (kLocatingReadings): between them the step is odometry predicting odometry.
std::vector<double> stepHeldOut(const LandmarkObservations& obs, const JointResult& fit,
                                const JointConfig& cfg);

}  // namespace lidarcal::diagnosis::sequence
