// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Radius of a landmark estimated jointly over all its observations (Alhashimi et al. 2021 section
// 3.1: the radius is known or "not difficult to obtain" from the arcs): one radius R and one centre
// c_k per observation minimise sum_k w_k sum_i (|p_ki - c_k| - R)^2, solved by Gauss-Newton with
// the centres eliminated (Schur complement on R). Observations are weighted by w_k = 1 / range_k^4
// (triangulation noise grows about with the square of the range, Alhashimi et al. 2016 eq. 1), so
// the near, least distorted arcs dominate.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "detectors/circle_fit.hpp"

namespace lidarcal::detectors {

/// The arc of one observation of a landmark, in its sensor frame (sensor at the origin).
struct ArcObservation {
  std::vector<Eigen::Vector2d> points;  ///< inlier points, metres
  Circle2 start;  ///< initial circle (the free fit, or any circle behind the arc)
};

struct RadiusEstimate {
  FitStatus status = FitStatus::too_few_points;  ///< ok, or why no radius could be estimated
  double radius_m = 0.0;                         ///< joint radius, metres
  std::vector<Circle2> centres;  ///< per observation: the circle with the joint radius
  double rms_m = 0.0;            ///< weighted RMS residual, metres
  int iterations = 0;            ///< Gauss-Newton iterations
};

/// Joint radius of one landmark; the radius is kept within [radius_min_m, radius_max_m].
RadiusEstimate estimateJointRadius(const std::vector<ArcObservation>& arcs, double radius_min_m,
                                   double radius_max_m, int max_iterations = 100);

}  // namespace lidarcal::detectors
