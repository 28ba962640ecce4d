// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The joint maximum-likelihood calibration of odometry (wheel radii, axle), the laser's
// mounting and its range bias from a drive among poles (model: drive.hpp). Every pose and every
// pole centre is a parameter of the same fit; the covariance of the calibrated quantities is the
// inverse of their Fisher information with the poses and poles eliminated (its Schur
// complement), which at the truth is the Cramer-Rao bound of the problem.
//
// Censi et al. 2013 calibrate the same odometry and mounting assuming the laser's ranges are
// exact; holding a_0 = a_1 = 0 here is that assumption.

#include <cmath>
#include <map>
#include <vector>

#include <Eigen/Core>

#include "common/status.hpp"
#include "odometry/drive.hpp"

namespace lidarcal::odometry {

/// Everything the fit estimates: the calibrated quantities, every pose and every pole.
struct DriveState {
  DriveParameters params;
  std::vector<Eigen::Vector3d> poses;    ///< per scan (x, y, heading); poses[0] is the origin
  std::map<int, Eigen::Vector2d> poles;  ///< centres in the world frame, by pole
};

struct DriveFitSetup {
  DriveParameters initial;  ///< start of the fit and the values of the held parameters
  EstimatedSet estimated = kEstimateAllButScale;
  DriveNoise noise;
  /// wheel radii and axle that set the odometry's noise (drive.hpp); the initial ones when unset
  OdometryParameters nominal;
  bool has_nominal = false;
  const OdometryParameters& noiseNominal() const {
    return has_nominal ? nominal : initial.odometry;
  }
};

struct DriveInformation {
  /// ok, or not_identifiable when the data leave a combination of the estimated parameters
  /// undetermined (inseparable lists them)
  Status status;
  /// Fisher information of the eight parameters with poses and poles eliminated; rows and
  /// columns of held parameters are zero
  Matrix8 information = Matrix8::Zero();
  /// its inverse over the estimated parameters (zero for held ones, and when not ok)
  Matrix8 covariance = Matrix8::Zero();
  /// directions along which the data do not change, in the parameters' units with the largest
  /// component 1 (a step along one changes no prediction, to first order)
  std::vector<Vector8> inseparable;
};

/// The information of `state`'s parameters in `record`, evaluated at `state` (at the truth this
/// is the Cramer-Rao bound's inverse).
DriveInformation driveInformation(const DriveRecord& record, const DriveState& state,
                                  const DriveFitSetup& setup);

struct DriveFit {
  /// ok; too_few_samples (no step or no sighting); solver_failed; not_identifiable
  Status status;
  DriveState state;  ///< the estimate (meaningful unless too_few_samples or solver_failed)
  DriveInformation information;
  int iterations = 0;
  /// half the sum of squared normalised residuals at the estimate
  double cost = 0.0;
  /// the a-posteriori variance factor: squared normalised residuals over their degrees of
  /// freedom (residuals minus free parameters); 1 in expectation when the stated noise is right
  double variance_factor = 0.0;
  /// squared normalised residuals summed by kind: odometry translation, odometry heading,
  /// range (of sightings, or of beams when fitted by beam), bearing
  Eigen::Vector4d squared_by_kind = Eigen::Vector4d::Zero();
  bool ok() const { return status.ok(); }
  /// square roots of the covariance's diagonal: the spread the stated noise implies
  Vector8 standardErrors() const;
  /// the same with the noise scaled by the variance factor, as the data show it
  Vector8 scaledStandardErrors() const { return standardErrors() * std::sqrt(variance_factor); }
};

/// The fit: dead reckoning with the initial parameters, poles placed from their sightings, then
/// Gauss-Newton (Levenberg-Marquardt) over everything. Deterministic. Never throws on data.
DriveFit fitDrive(const DriveRecord& record, const DriveFitSetup& setup);

/// The variance factor of each kind of residual (odometry translation, odometry heading, range,
/// bearing): its squared normalised residuals over its redundancy (Foerstner's redundancy
/// numbers summed over its rows: rows minus the trace of the hat matrix over them; they sum to
/// the degrees of freedom). Which stated noise is off, and by how much (the square root); a
/// factor's relative SD is about sqrt(2 / redundancy); NaN for a kind without rows. Costs a
/// solve per residual row.
struct VarianceByKind {
  Eigen::Vector4d factor = Eigen::Vector4d::Zero();
  Eigen::Vector4d redundancy = Eigen::Vector4d::Zero();
};
VarianceByKind varianceByKind(const DriveRecord& record, const DriveFitSetup& setup,
                              const DriveFit& fit);

/// Dead reckoning: the poses the wheels give for `params`, from the origin.
std::vector<Eigen::Vector3d> deadReckoning(const DriveRecord& record,
                                           const OdometryParameters& params);

}  // namespace lidarcal::odometry
