// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to refineJoint() (joint_refinement.hpp): the joint refinement as a problem with
// named steps. Parameter blocks (poses, centres, radius, bias, landmark offsets, the global
// effect terms, odometry scale) live in the object; every solve rebuilds a Ceres problem over
// them from the readings selected at the current estimate:
//
//   initialise  -> model, parameter blocks, reading window, drift reference, readings
//                  (joint_problem.cpp, with the per-reading geometry)
//   solve loop  -> [select readings] geometry, sigmas, weights -> residuals (joint_residuals.cpp)
//                  -> Ceres -> re-estimate the noise law (and the mixed-pixel fraction) until it
//                  settles (joint_solve.cpp)
//   summarise   -> estimates, priors' NLL, effects, likelihood and criteria, bearing residuals,
//                  covariance of the bias, radius and centres (joint_summary.cpp)
// The cost functions' factories are in joint_costs.cpp.

#include <map>
#include <vector>

#include <ceres/ceres.h>

#include "calibration/joint_costs.hpp"
#include "calibration/joint_refinement.hpp"

namespace lidarcal::calibration::joint {

class JointProblem {
 public:
  /// Throws std::invalid_argument for an invalid config or one initial pose per stop missing.
  JointProblem(const LandmarkObservations& obs, const JointInit& init, const JointConfig& config);
  /// Runs the refinement once; the result says why when it failed (JointResult::message).
  JointResult run();

 private:
  /// One beam reading on a landmark.
  struct Reading {
    std::size_t stop;
    std::size_t scan;
    int landmark;
    double angle_rad;
    double y_m;
    bool edge;
    double darkness;  ///< ln(I_ref / I) of its return (0: no intensity recorded)
  };

  // initialise
  void initialiseModel();
  void initialiseParameters();
  std::vector<double> alphaVector() const { return std::vector<double>(alpha_, alpha_ + n_alpha_); }
  void startEffectTerms();
  void initialiseReadingWindow();
  void initialiseDriftReference();
  void initialiseReferenceIntensity();
  void selectReadings();

  // per reading at the current estimate
  void updateGeometry();
  double meanOf(std::size_t i, const BiasPolynomial& f) const;
  double sigmaOf(std::size_t i, const RangeModel& m) const;
  std::vector<double> residualsNow(const BiasPolynomial& f) const;
  void updateResponsibilities(const std::vector<double>& res);

  // residuals
  void addResiduals(ceres::Problem& problem, bool robust);
  void addReading(ceres::Problem& problem, bool robust, const Reading& r, double angle, double y,
                  double inv, double count);
  bool addPooledReadings(ceres::Problem& problem, bool robust);
  void addKnownRanges(ceres::Problem& problem, bool robust);
  void addPosePriors(ceres::Problem& problem);
  void fixInactiveTerms(ceres::Problem& problem);
  void fixKnownGeometry(ceres::Problem& problem);

  // solve loop
  bool solve(int outer);
  bool reestimateNoise(int outer);
  void reestimateMixedFraction(const std::vector<double>& res);
  void fitNoiseLaw(const std::vector<double>& res, const BiasPolynomial& f);
  void fitStudent(const std::vector<double>& res, const BiasPolynomial& f);
  void fitCellScale(const std::vector<double>& res);
  double workingSigma(std::size_t i, const RangeModel& m) const;
  double profileNoise(NoiseModel n, double g, double delta, const std::vector<std::size_t>& in,
                      const std::vector<double>& res, const BiasPolynomial& f,
                      double* sigma_e) const;

  // summarise
  void reportEstimates();
  void reportPriorLikelihood();
  void boundStepScale(ceres::Problem& problem) const;
  void reportEffects();
  void reportLikelihood();
  void reportBearingResiduals();
  void computeCovariance();

  const LandmarkObservations& obs_;
  const JointInit& init_;
  const JointConfig& config_;
  const JointEffects& fx_;
  JointResult out_;
  bool motion_ = false;  ///< motion prior in use (and at least two stops)

  // Parameter blocks, all in one array (params_) in a fixed order: poses, centres (by id), bias,
  // landmark offsets (by id), radius, the global terms, odometry scale. Ceres orders the
  // covariance's columns by the blocks' addresses; one array makes that order (and so the last
  // digits of every standard error) independent of where the allocator put each block.
  std::vector<double> params_;
  std::vector<double*> poses_;      ///< x, y, heading per stop
  std::map<int, double*> centres_;  ///< x, y per landmark
  double* alpha_ = nullptr;         ///< alpha_0..alpha_n
  std::size_t n_alpha_ = 0;
  std::map<int, double*> offsets_;  ///< landmark offsets; the first landmark is the reference (0)
  double* radius_ = nullptr;
  double* globals_ = nullptr;         ///< drift, zero-angle offset, incidence bias
  double* scale_ = nullptr;           ///< odometry scale
  double gamma_ = 0.0;                ///< incidence noise exponent
  double delta_ = 0.0;                ///< dark-surface noise exponent
  double reference_intensity_ = 0.0;  ///< I_ref of the darkness (0: no intensity recorded)
  double mixed_fraction_ = 0.0;
  double dof_ = 0.0;   ///< Student-t degrees of freedom (0: Gaussian noise)
  double grid_ = 0.0;  ///< grid of the readings under the quantised model (0: none)

  double window_max_ = 0.0;           ///< upper end of the reading window
  double previous_noise_size_ = 0.0;  ///< size of the noise law before the last re-estimation
  double t_ref_ = 0.0;                ///< drift reference scan
  bool pool_ = false;  ///< pool repeated scans (JointConfig::pool_repeated_scans, when allowed)

  // Per reading.
  std::vector<Reading> readings_;
  std::vector<BeamGeometry> geo_;
  std::vector<double> sigma_;
  std::vector<double> weight_;  ///< 1 - mixed-pixel responsibility, or the Student t's EM weight
};

}  // namespace lidarcal::calibration::joint
