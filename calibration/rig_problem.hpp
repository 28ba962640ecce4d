// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to calibrateRig() (rig_calibrate.hpp): one fit of the rig at fixed bias orders, flips
// and gauge, as a problem with named steps:
//
//   initialise -> pooled beams (one per sensor, stop, pole and beam), parameter blocks, starts
//   solve loop -> [select beams] weights from each sensor's noise -> residuals + priors -> Ceres
//                 -> re-estimate each sensor's noise (rig_noise.hpp) until it settles
//   summarise  -> covariance (J^T J inverted over the free parameters), leverages, noise with
//                 their degrees of freedom, one more solve, estimates and standard errors

#include <cstddef>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Core>

#include "calibration/rig_calibrate.hpp"
#include "calibration/rig_noise.hpp"

namespace lidarcal::calibration::rig {

/// What one fit holds fixed: the outcome of calibrateRig's decisions.
struct FitSetup {
  std::vector<int> orders;              ///< bias order per sensor
  std::vector<double> flips;            ///< +1 / -1 per sensor
  RigFrame frame = RigFrame::relative;  ///< vehicle or relative
  bool scale_held = false;              ///< reference alpha_1 held (the range scale's gauge)
  bool motion = false;  ///< odometry steps between consecutive stops (else a prior per stop)
  std::vector<bool> stop_held;  ///< per stop: held at its start (gauge without recorded poses)
  /// Pooled beams to fit (indices of RigProblem::selected() of an earlier fit of the same
  /// observations), so that fits of other orders are compared on the same readings; null: by
  /// the lateral rule at the current estimate.
  const std::vector<std::size_t>* selection = nullptr;
};

/// Readings of one beam on one pole at one stop, pooled.
struct PooledBeam {
  std::size_t sensor = 0, stop = 0;
  int pole = 0;
  double angle_rad = 0.0;  ///< beam angle in the sensor's frame
  double n = 0.0;          ///< readings
  double mean_m = 0.0;     ///< their mean
  double within_ss = 0.0;  ///< sum of squared deviations around the mean, m^2
};

class RigProblem {
 public:
  RigProblem(const RigObservations& obs, const RigConfig& config, const FitSetup& setup);
  /// Runs the fit; the result's status says why when it failed.
  RigResult run();
  /// The pooled beams the last solve fitted (indices into the pooled beams, which depend on the
  /// observations only).
  const std::vector<std::size_t>& selected() const { return used_; }

 private:
  // initialise
  void poolBeams();
  void initialiseParameters();
  void initialisePoles();
  // per beam at the current estimate
  double distanceOf(const PooledBeam& b, double* lateral) const;
  double biasOf(std::size_t sensor, double d) const;
  void selectBeams(bool all);
  std::vector<std::vector<NoiseSample>> noiseSamples() const;
  // residuals and solves
  void addResiduals(ceres::Problem& problem, bool robust,
                    std::vector<ceres::ResidualBlockId>* data_blocks);
  void addVehiclePriors(ceres::Problem& problem);
  void holdGauge(ceres::Problem& problem);
  bool solve(bool hold_bias, bool robust);
  bool reestimateNoise();
  // summarise
  bool computeCovariance();
  Eigen::MatrixXd covarianceBlock(std::size_t offset, std::size_t size) const;
  double summariseSensors(std::size_t* samples_used);
  void summarisePoles();
  void summariseRelativeMountings();
  void summarise();

  double* vehicle(std::size_t k) { return &params_[3 * k]; }
  double* mount(std::size_t s) { return &params_[mount_offset_ + 3 * s]; }
  double* pole(std::size_t index) { return &params_[pole_offset_ + 2 * index]; }
  double* radius() { return &params_[radius_offset_]; }
  double* alpha(std::size_t s) { return &params_[alpha_offset_[s]]; }
  const double* alpha(std::size_t s) const { return &params_[alpha_offset_[s]]; }
  std::size_t poleIndex(int id) const;

  const RigObservations& obs_;
  const RigConfig& config_;
  const FitSetup& setup_;
  RigResult out_;

  // Parameter blocks in one array, in a fixed order: vehicle poses, mountings, poles (by id),
  // radius, each sensor's alpha (the covariance's columns follow it).
  std::vector<double> params_;
  std::size_t mount_offset_ = 0, pole_offset_ = 0, radius_offset_ = 0;
  std::vector<std::size_t> alpha_offset_;
  std::vector<int> pole_ids_;  ///< sorted
  double zero_scale_ = 0.0;    ///< the motion prior's step-scale block, held at 0

  std::vector<PooledBeam> beams_;
  std::vector<std::size_t> used_;   ///< beams selected (indices into beams_)
  std::vector<double> leverage_;    ///< per used beam
  std::vector<SensorNoise> noise_;  ///< per sensor
  std::vector<std::size_t> readings_per_sensor_;
  Eigen::MatrixXd covariance_;  ///< over the free parameters (columns_)
  std::vector<int> column_of_;  ///< parameter index -> covariance column (-1: held)
};

}  // namespace lidarcal::calibration::rig
