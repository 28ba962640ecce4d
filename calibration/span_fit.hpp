// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The range model from wall-to-wall spans (REF.json `spans`; span_walls.hpp finds the walls),
// alone or with tape distances (REF.json `distances`): the counterpart for spans of Alhashimi et
// al. 2016's calibration against known distances (section 5, reference.hpp).
//
//   - A beam on wall w at angle phi reads f(p_w / cos(phi - n_w)) + noise: p_w is the sensor's
//     true perpendicular distance to the wall, n_w its normal direction.
//   - Given f, the wall's readings say where it is: (p_w, n_w) by least squares over its beam
//     means (wallDistance), with the variance of p_w from their scatter about the fit.
//   - Span k says p_a + p_b = S_k, within its sigma_m. f follows by generalised least squares of
//     the spans' residuals p_a(f) + p_b(f) - S_k, their covariance the meter's variance plus the
//     walls' (spans that share a wall share its error).
//   - A tape distance (distances[] entry) adds one residual: the mean of its readings against
//     the mean of f over their known distances, in distance units, with standard deviation
//     sqrt(sigma_tape^2 + sigma_read^2 / beams) (the term the joint refinement gives it).
//
// Only the spans fix the scale of a wall's distance. The spread of distances along one wall
// (p to p / cos 57 degrees) would identify f by itself if f depended on the distance alone, but
// an incidence-dependent reading mimics it (`diagnose` names incidence_bias): on the RPLIDAR room
// of docs/RESULTS.md the walls' straightness says alpha_0 = -73 +- 14 mm where the spans say
// +25 +- 5 mm. So a wall enters only through p_w(f), and what is identifiable is what the
// spans' residuals determine: one span, or several between the same two walls, determine one
// number, an offset f(d) = d + alpha_0 ("order 0"); spans between pairs of walls of different
// lengths determine a scale as well (order 1), and so on (the rank of their Jacobian).
// The order is chosen by leave-one-group-out cross-validation: the spans between one pair of
// walls form a group (they repeat one sum: leaving one out would leave its walls measured), each
// tape distance another (the unit of independent information, as the stop is in reference.hpp); the
// covariance of alpha is the inverse information, scaled by chi^2 / dof when that exceeds 1 (the
// entries disagree by more than their sigma_m says). The model assembled from these fits:
// span_calibration.hpp.

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calibration/reference.hpp"
#include "calibration/span_walls.hpp"
#include "common/reference.hpp"

namespace lidarcal::calibration {

/// What a wall's readings say about it under the bias f.
struct WallDistance {
  bool ok = false;          ///< false: too few beams, or the fit left the sensor's side of the wall
  double distance_m = 0.0;  ///< true perpendicular distance p_w, metres
  double normal_rad = 0.0;  ///< normal direction n_w, sensor frame, radians
  double variance_m2 = 0.0;  ///< variance of p_w from the beam means' scatter about the fit, m^2
};

/// (p_w, n_w) minimising the squared differences between the wall's beam means and
/// f(p_w / cos(phi - n_w)) (Gauss-Newton from the raw line).
WallDistance wallDistance(const SpanWall& wall, const BiasPolynomial& f);

/// The known-distance readings of one tape distance (a distances[] entry).
struct TapeEntry {
  std::size_t entry = 0;         ///< index into Reference::distances
  std::size_t stop = 0;          ///< its stop
  double reference_m = 0.0;      ///< the measured distance, metres
  std::vector<double> d_m, y_m;  ///< true distances and raw readings of its beams, metres
  std::size_t beams = 0;         ///< distinct beams among them
  double sigma_m = 0.002;        ///< the measurement's standard deviation, metres
};

/// The entries of a span fit: the spans found in the data and the tape distances.
struct SpanProblem {
  std::vector<SpanWall> walls;
  struct Span {
    /// REF.json index, stop, indices into walls
    std::size_t entry = 0, stop = 0, wall_a = 0, wall_b = 0;
    double distance_m = 0.0, sigma_m = 0.002;  ///< the measured span and its standard deviation
  };
  std::vector<Span> spans;       ///< the matched spans, in REF.json order
  std::vector<TapeEntry> tapes;  ///< the tape distances, in REF.json order
  std::size_t entries() const { return spans.size() + tapes.size(); }
  /// "spans[2]" or "distances[0]" for entry k (spans first).
  std::string name(std::size_t k) const;
  /// The unit of independent information entry k belongs to: spans between the same two walls
  /// measure one sum (at different places along the walls) and form one group; every tape
  /// distance is a group of its own. Groups are numbered 0, 1, ... in order of first entry.
  std::vector<std::size_t> groups() const;
};

/// The problem from the matched spans (every match ok) and the tape readings (reference.hpp).
SpanProblem spanProblem(const SpanReadings& spans, const Reference& ref,
                        const std::vector<KnownReading>& tape);

/// One bias model fitted to some of the entries.
struct SpanModelFit {
  int order = 0;              ///< 0: the offset f(d) = d + alpha_0; n >= 1: a polynomial of order n
  bool identifiable = false;  ///< the entries used determine every coefficient
  std::vector<double> alpha;  ///< alpha_0..alpha_n (order 0: {alpha_0, 1})
  Eigen::MatrixXd covariance;  ///< of alpha (order 0: 2x2, zero for the fixed alpha_1)
  double chi2 = 0.0;           ///< sum of the whitened squared residuals
  std::size_t dof = 0;         ///< entries used - coefficients
  /// per entry (all of them): what the sensor says with this model - what was measured, metres
  Eigen::VectorXd error_m;
};

/// Fits the model of `order` to the entries with use[k] (generalised least squares, Gauss-Newton
/// from f(d) = d); not identifiable when the used entries do not determine every coefficient.
SpanModelFit fitSpanModel(const SpanProblem& problem, int order, const std::vector<bool>& use);

/// Every entry's error under f (as SpanModelFit::error_m), e.g. the raw sensor's with f(d) = d;
/// empty when a wall cannot be placed under f.
Eigen::VectorXd entryErrors(const SpanProblem& problem, const BiasPolynomial& f);

}  // namespace lidarcal::calibration
