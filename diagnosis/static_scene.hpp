// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Diagnosis of repeated scans from one pose of any scene (diagnosis/diagnosis.hpp): the
// characterisation setting of Alhashimi et al. 2016, where each beam over the scans is a batch at a
// constant distance.
//
// Without a true distance, what is identifiable:
//   - per beam (direction bin): the mean reading m_b and the spread around it, so the noise law
//     (spread against m_b, Alhashimi et al. 2016 eqs. 10-15 generalised to a free exponent), the
//     shape of the noise (tails, quantisation), anything shared over time (drift over the scans)
//     and the readings at depth discontinuities (mixed pixels);
//   - on straight surfaces (wall lines fitted to the beam means): the incidence of each beam,
//     hence noise against incidence; and, with the walls as a geometric reference, a range
//     offset alpha_0 (a constant added along each beam bends a straight wall: its
//     perpendicular displacement is alpha_0 cos(incidence)) and an incidence-dependent bias.
//   - not identifiable: the range scale alpha_1 (it scales the whole room), per-surface offsets
//     (each wall's own line absorbs its offset), anything about poses (one pose: heading errors,
//     zero-angle offset and step length do not apply).
// Likelihood of the readings: a beam's readings given its mean (held out by scan) times its
// mean given the wall model, N(line + bias terms, tau^2 + s_b^2 / n_b) with a wall roughness tau
// (held out by bin, leave one out). Baseline: f(d) = alpha_0 + d, sigma = sigma_e f(d)^2
// (Alhashimi et al. 2016 eq. 1), Gaussian, no drift, no incidence dependence.

#include <cstdint>
#include <limits>
#include <vector>

#include "diagnosis/diagnosis.hpp"

namespace lidarcal::diagnosis {

/// Repeated scans from one pose: every reading with its beam angle and scan.
struct StaticScans {
  struct Reading {
    double angle_rad = 0.0;  ///< beam angle in the sensor frame, radians
    double range_m = 0.0;    ///< reading, metres (finite, > 0)
    std::uint32_t scan = 0;  ///< scan index (time order)
    /// return intensity (sensor units), NaN when not recorded
    double intensity = std::numeric_limits<double>::quiet_NaN();
  };
  std::vector<Reading> readings;   ///< all returns of all scans
  std::size_t scans = 0;           ///< scans (including scans without returns)
  std::size_t beams_per_scan = 0;  ///< median beams per scan (angular resolution), 0 when unknown
  double range_min_m = 0.0;        ///< sensor window
  double range_max_m = 1e9;
  /// the readings carry an intensity (a covariate of the tails: dark surfaces)
  bool has_intensity = false;
};

/// A straight surface found in the beam means.
struct WallLine {
  double normal_rad = 0.0;  ///< direction of the line's normal from the sensor, radians
  /// perpendicular distance from the sensor to the line (the model's d), metres
  double distance_m = 0.0;
  double first_angle_rad = 0.0, last_angle_rad = 0.0;  ///< beam angles it spans
  std::size_t bins = 0;                                ///< direction bins on it
  double rms_m = 0.0;  ///< RMS of the bin means about the model (range units)
};

/// Diagnoses. `walls` (optional) receives the fitted wall lines (the geometric reference).
DiagnosisResult diagnoseStatic(const StaticScans& data, const DiagnoseConfig& config,
                               std::vector<WallLine>* walls = nullptr);

}  // namespace lidarcal::diagnosis
