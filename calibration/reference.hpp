// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Calibration against what a user measured (Alhashimi et al. 2016 section 5: the range model fitted
// to readings whose true distance is known). A reference distance to a pole's centre (or to a wall)
// at one stop gives every beam on that target a known true distance; the range model is then fitted
// to those readings:
//   - the noise exponent k of sigma = sigma_e f(d)^k by Alhashimi et al. 2016's test (eqs. 10-15)
//     on the repeated readings of one beam at one stop (a time-of-flight lidar gives k = 0, a
//     triangulation lidar k = 2);
//   - f for every order by weighted least squares with weights 1 / f(d)^(2k), iterated (the
//     generalised form of Alhashimi et al. 2016's closed form, eqs. 21-26);
//   - the order by leave-one-stop-out cross-validation: the readings of one stop share the
//     error of its one tape measurement (and whatever the model misses at that distance), so
//     the stop, not the reading, is the unit of independent information;
//   - the covariance of alpha clustered by stop (the jackknife over the stops), for the same
//   reason.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calibration/calibrate.hpp"
#include "calibration/joint_refinement.hpp"
#include "common/calibration_model.hpp"
#include "common/landmark_observations.hpp"
#include "common/reference.hpp"

namespace lidarcal::calibration {

struct ReferenceConfig {
  /// Beams on a pole are used while they pass within this fraction of the radius from its centre
  /// (incidence below about 45 degrees at 0.7): near the tangent the distance along the beam
  /// changes fast with the centre and the reading carries edge effects. Default 0.7.
  double lateral_fraction = 0.7;
  /// Beams on a wall are used while they meet it within this angle of its normal, radians.
  /// Default 1.0 (57 degrees).
  double max_wall_incidence_rad = 1.0;
  /// With a bearing given, the target's detected bearing must lie within this, radians. Default
  /// 0.2.
  double max_bearing_error_rad = 0.2;
  /// The target's measured distance must lie within this fraction of the reference distance
  /// plus 0.1 m (with or without a bearing). Default 0.25.
  double max_distance_error_fraction = 0.25;
  void validate() const;  ///< throws std::invalid_argument
};

/// How one reference distance was found in the data, and what the sensor measured there.
struct ReferenceMatch {
  std::size_t entry = 0;  ///< index into Reference::distances
  std::size_t stop = 0;   ///< its stop
  ReferenceTarget target = ReferenceTarget::landmark;
  double reference_m = 0.0;  ///< the measured (tape) distance, metres
  /// Nearest true distance of a beam on the target, metres: reference_m less the pole's radius
  /// (what the range model sees), reference_m for a wall.
  double surface_m = 0.0;
  int landmark = 0;           ///< matched landmark id (landmark targets), 0 otherwise
  std::size_t sightings = 0;  ///< scans of the stop in which the target was found
  /// what the scans say: mean detected centre range, or mean perpendicular wall distance, metres
  double measured_m = 0.0;
  double measured_se_m = 0.0;  ///< standard error of that mean over the scans, metres
  /// mean detected bearing of the target (centre, or wall normal), sensor frame
  double bearing_rad = 0.0;
  std::size_t readings = 0;   ///< known-distance readings it gave
  std::string status = "ok";  ///< ok, or why the entry could not be used
  bool ok() const { return status == "ok"; }
};

/// One reading whose true distance is known from a reference measurement.
struct KnownReading {
  std::size_t entry = 0;   ///< reference distance it comes from
  std::size_t stop = 0;    ///< stop (the unit of independent information)
  std::size_t scan = 0;    ///< scan index
  std::uint32_t beam = 0;  ///< beam index (kUnknownBeam when not comparable across scans)
  double d_m = 0.0;        ///< true distance along the beam, metres
  double y_m = 0.0;        ///< raw reading, metres
  double angle_rad = 0.0;  ///< beam angle in the sensor frame, radians
  /// stated error of the entry's measured distance (REF.json sigma_m), metres
  double tape_sigma_m = 0.002;
};

struct ReferenceReadings {
  std::vector<KnownReading> readings;
  std::vector<ReferenceMatch> matches;  ///< one per reference distance, in order
};

/// Finds each reference distance's target at its stop (obs.sightings for poles, obs.walls for
/// walls) and turns the beams on it into known-distance readings. `radius_m` <= 0: each pole's
/// radius is the median of its detected radii at that stop.
ReferenceReadings knownReadings(const LandmarkObservations& obs, const Reference& ref,
                                double radius_m, const ReferenceConfig& config = {});

/// A polynomial range model fitted to readings grouped in clusters (the stops).
struct ClusteredFit {
  std::vector<double> alpha;  ///< alpha_0..alpha_n
  /// of alpha, clustered by stop: leave-one-stop-out jackknife (the sandwich when fewer than 2
  /// stops)
  Eigen::MatrixXd covariance;
  double sigma_e = 0.0;             ///< noise scale of sigma = sigma_e f(d)^k
  double neg_log_likelihood = 0.0;  ///< Gaussian NLL of the readings under the fit
  /// leave-one-stop-out mean squared error (weighted by the noise law), NaN when not computed
  double cv_mse_m2 = 0.0;
};

/// Weighted least squares of y on 1, d, ..., d^order with weights 1 / f(d)^(2 exponent),
/// iterated to a fixed point, and its covariance clustered by `cluster` (jackknife). `cluster[i]`
/// labels reading i. `factor[i]`, when given, multiplies reading i's weight in the fit (the
/// random-effects weights of calibration/discrepancy.hpp); sigma_e and the likelihood stay the
/// noise law's.
ClusteredFit fitClustered(const std::vector<double>& d, const std::vector<double>& y,
                          const std::vector<std::size_t>& cluster, int order, double exponent,
                          const std::vector<double>& factor = {});

/// The readings of each matched reference distance summarised for the joint refinement (one
/// KnownRange per entry with readings; its tape sigma from REF.json).
std::vector<KnownRange> knownRanges(const ReferenceReadings& known, const Reference& ref);

/// Alhashimi et al. 2016's noise-exponent test (eqs. 10-15) on the repeated readings of each beam
/// on one target at one stop; fills the exponent_* fields of `fits` and returns the exponent k of
/// sigma = sigma_e f(d)^k to fit with: the test's, else 0 for config.noise constant and 2 otherwise
/// (with the reason in fits.unavailable).
double testReadingNoise(const std::vector<KnownReading>& readings, const CalibrationConfig& config,
                        NoiseFits& fits);

/// The noise law sigma = sigma_e f(d)^exponent: constant for 0, squared for 2, power otherwise.
void setNoiseLaw(NoiseModel& noise, double exponent, double sigma_e);

/// The range model from known-distance readings (method "reference"): the noise exponent by
/// Alhashimi et al. 2016's test, the order by leave-one-stop-out cross-validation, standard errors
/// clustered by stop, and the model discrepancy over the entries (calibration/discrepancy.hpp: the
/// sensor's scatter about the polynomial between measured distances, net of the entries' stated
/// tape errors). Where the entries state a tape error or show a discrepancy, the chosen order is
/// refitted with the random-effects weights (randomEffectsFactors), so that each entry counts by
/// its whole variance rather than by its readings. The result's status says why not when the
/// readings cannot support a model (fewer than 3 stops, or fewer stops than coefficients + 1).
CalibrationModel calibrateWithReference(const std::vector<KnownReading>& readings,
                                        const CalibrationConfig& config, double range_min_m = 0.0,
                                        double range_max_m = 1e9);

}  // namespace lidarcal::calibration
