// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How a result ended: one code a program can test and one message a user can act on. The
// calibration (model.json "diagnostics.status"), the joint refinement and the diagnosis report
// their outcome with it; exceptions are left for bad input at the edges (io/, the command line)
// and for programming errors. The codes' meanings for a user: docs/ERRORS.md.

#include <optional>
#include <string>
#include <string_view>

namespace lidarcal {

enum class StatusCode {
  ok,
  // calibration (model.json)
  too_few_stops,            ///< the sequence has fewer stops than a triangulation needs
  no_baseline,              ///< the stops do not span a baseline (the sensor never moved)
  no_usable_landmark,       ///< no landmark could be triangulated
  too_few_observations,     ///< too few landmark-stop distances for the range model
  joint_failed,             ///< the joint refinement found no usable solution
  no_radius,                ///< the landmark radius is neither given nor estimable
  too_few_reference_stops,  ///< calibrate --reference: too few stops with a known distance
  no_invertible_order,      ///< calibrate --reference: no order gives an invertible model
  /// calibrate --effects dark_surface: the readings record no intensity (or one value)
  no_intensity,
  exception,  ///< studies: a trial threw (the message is what)
  // joint refinement
  not_run,           ///< no refinement was computed (a default result)
  too_few_readings,  ///< fewer readings than parameters
  no_readings,       ///< no reading left to fit
  solver_failed,     ///< Ceres returned no usable solution
  // diagnosis
  baseline_failed,          ///< the seeds' model could not be fitted
  calibration_failed,       ///< the baseline calibration behind a sequence diagnosis failed
  cross_validation_failed,  ///< no fold could be fitted
  too_few_scans,            ///< static data: too few scans from one pose
  too_few_beams,            ///< static data: too few beam directions return often enough
  too_few_walls,  ///< static data: the returns lie on straight surfaces over too narrow a sector
  // several sensors on one vehicle
  not_identifiable,  ///< the data leave a mounting (or another parameter) undetermined
  /// a sensor sees no pole another sensor sees, and nothing else ties their frames
  no_shared_landmark,
  // odometry and laser mounting (odometry/)
  too_few_samples,    ///< fewer intervals (samples) than the calibration needs
  degenerate_motion,  ///< the motion leaves a parameter undetermined (no turns, only straight
                      ///< lines)
  negative_axle,      ///< positive wheel radii would need a negative axle (a wheel's sign swapped)
};

/// The code's name as written in model.json and diagnosis.json ("ok", "joint_failed", ...).
const char* toString(StatusCode code);
/// The code of that name; nullopt for any other string.
std::optional<StatusCode> parseStatusCode(std::string_view name);

struct Status {
  StatusCode code = StatusCode::ok;
  /// Why not, and what to record instead, when not ok; a note a user should read when ok
  /// (e.g. how settled a solution is); may be empty.
  std::string message;
  bool ok() const { return code == StatusCode::ok; }
  const char* name() const { return toString(code); }
};

}  // namespace lidarcal
