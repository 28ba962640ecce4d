// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One simulated calibration run as the Monte Carlo study sees it: what the estimators get (the
// landmark observations) and the truth kept aside to score them. Both simulation levels
// (landmark level: Alhashimi et al. 2021 eqs. 3, 5, 8; scan level: ray casting and detection)
// produce it.

#include <cstdint>
#include <vector>

#include "common/landmark_observations.hpp"
#include "common/scene.hpp"

namespace lidarcal::studies {

/// A reading with its true distance (for the oracle and for the MSE ratio, Alhashimi et al. 2021
/// eq. 31).
struct TruthReading {
  std::size_t stop = 0;    ///< stop index
  int landmark = 0;        ///< true landmark id (1-based, as in the layout)
  std::uint32_t beam = 0;  ///< beam index in its scan
  double range_m = 0.0;    ///< raw reading, metres
  double true_m = 0.0;     ///< true distance along the beam, metres
};

struct Draw {
  LandmarkObservations obs;  ///< what calibration sees (ids as detected)
  /// True distance of every beam of every sighting (truth_m[i][j] for obs.sightings[i].beams[j]);
  /// NaN where the truth is unknown (a detection that is not on a landmark).
  std::vector<std::vector<double>> truth_m;
  /// Detected landmark id -> true landmark id (1-based; 0: not matched). Index 0 unused.
  std::vector<int> true_id;
  std::vector<Pose2> actual;  ///< true pose of each stop
};

/// Landmark-level draw (simulation/landmark_level.hpp with beams): sighting ids are the true ids.
/// Eq. 5: the centre bearing of landmark l at stop k is off by one v_lk ~ N(0, sigma_theta_rad^2),
/// the same in every scan of the stop (so the stop's mean bearing has exactly that noise and the
/// range readings, drawn along the true beams, do not depend on it). `rotate_beams`: the angles
/// of the sighting's beams turn by the same v_lk (the sensor reports the whole landmark turned);
/// otherwise they stay exact. Heading noise comes with the path (sigma_psi_rad) instead.
Draw drawLandmarkLevel(const std::vector<Cylinder>& landmarks, const PathSpec& path,
                       const RangeModel& sensor, double sigma_theta_rad, std::uint64_t seed,
                       bool rotate_beams);

/// Every landmark reading of a draw with its truth (the test set of the MSE ratio).
std::vector<TruthReading> truthReadings(const Draw& draw);

/// The scans of each stop reduced to one: every beam's readings averaged over the stop's scans
/// (readings of one beam at one stop share their true distance, so for Gaussian noise the mean
/// carries all the information about the bias), centre bearings averaged on the circle. Used to
/// feed the joint refinement at a cost that does not grow with the scans per stop.
LandmarkObservations averageScans(const LandmarkObservations& obs);

}  // namespace lidarcal::studies
