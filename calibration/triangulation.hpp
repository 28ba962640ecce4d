// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Landmark centres from bearings (Alhashimi et al. 2021 section 3.1, eqs. 18-25): each stop k that
// sees landmark l gives a line through the stop along the bearing; the centre is the weighted
// least-squares point closest to all lines, with the commanded stop positions in place of the
// unknown true ones (eq. 21-23).

#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/landmark_observations.hpp"

namespace lidarcal::calibration {

/// Weights of the bearing lines.
enum class LineWeights {
  /// eq. 25: W* = sigma_s^-2 I + sigma_theta^-2 diag(1 / var(d~_lk)), var from repeated scans
  paper,
  residual,  ///< 1 / (sigma_s^2 + d~_lk^2 sigma_theta^2): the variance of the residual of eq. 24
  uniform,   ///< ordinary least squares
};

struct TriangulationConfig {
  LineWeights weights = LineWeights::paper;  ///< how the lines are weighted
  double sigma_s_m = 0.02;  ///< assumed std. dev. of the stop positions (eq. 8), metres
  /// assumed std. dev. of the world bearing (eq. 5), radians (1 degree)
  double sigma_theta_rad = 0.0175;
  int min_stops = 3;                      ///< fewer stops: the landmark is reported, not solved
  double min_bearing_spread_rad = 0.087;  ///< lines must span at least this angle (5 degrees)
  double max_condition = 1e8;             ///< larger condition number of H'WH: ill-conditioned
  void validate() const;                  ///< throws std::invalid_argument on a meaningless setting
};

/// A landmark as seen from one stop: averages over the scans taken there.
struct StopBearing {
  std::size_t stop = 0;            ///< stop index
  double bearing_world_rad = 0.0;  ///< commanded heading + circular mean of the centre bearings
  double range_m = 0.0;            ///< mean raw reading of the beam nearest the centre (d~_lk)
  double range_var_m2 = 0.0;  ///< sample variance of that reading over the scans (0 with one scan)
  int scans = 0;              ///< scans averaged
};

enum class TriangulationStatus { ok, too_few_stops, degenerate_geometry, ill_conditioned };
const char* toString(TriangulationStatus s);

struct LandmarkEstimate {
  int id = 0;                   ///< landmark id
  double x_m = 0.0, y_m = 0.0;  ///< centre in the world (commanded) frame
  /// of (x, y), m^2, scaled by the residual variance
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  int stops = 0;                    ///< stops that saw it
  double bearing_spread_rad = 0.0;  ///< angle between the most different bearing lines
  double condition = 0.0;           ///< condition number of H'WH
  double residual_rms_m = 0.0;      ///< RMS distance of the lines from the centre
  TriangulationStatus status = TriangulationStatus::ok;
  std::string message;  ///< what a user can do when status != ok
  bool ok() const { return status == TriangulationStatus::ok; }
};

/// Index of the beam of a sighting nearest to its centre bearing.
std::size_t centralBeam(const Sighting& s);

/// Per-stop averages for one landmark (stops that did not see it are absent).
std::vector<StopBearing> stopBearings(const LandmarkObservations& obs, int landmark);

/// Solves eq. 23 for one landmark from its per-stop bearings and the commanded poses.
LandmarkEstimate triangulate(int id, const std::vector<StopBearing>& bearings,
                             const std::vector<Pose2>& commanded,
                             const TriangulationConfig& config);

/// Every landmark id present in the observations, sorted.
std::vector<int> landmarkIds(const LandmarkObservations& obs);

/// Triangulates every landmark.
std::vector<LandmarkEstimate> triangulateAll(const LandmarkObservations& obs,
                                             const TriangulationConfig& config);

}  // namespace lidarcal::calibration
