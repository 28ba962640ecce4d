// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// FastSLAM 1.0 with known data association (Sharma 2020 ch. 3.1, after Montemerlo et al., its
// ref. [8]): every particle carries a pose and one 2x2 EKF per landmark. For each stop the
// particles are moved by the commanded motion plus sampled process noise (Sharma 2020 ch. 3.1,
// x(t) = A x(t-1) + B u + w), then each range-bearing observation, from any sensor, updates the
// particle's landmark EKF under the assumed noise of that sensor and multiplies the particle's
// weight by the innovation likelihood (ch. 3.1, fig. 13). After a stop's observations, the
// predicted error of each observation (ch. 3.2, fig. 16-17) is
//   e_i = reading - h(pose_i, landmark_i)       for each particle i (range and wrapped bearing),
// and the observation contributes the particle-weighted mean error sum_i w_i e_i and the
// particle-weighted mean squared error sum_i w_i e_i^2 to its sensor's error samples.
//
// Randomness: one stream makeRng(seed, stream); per stop, three normals per particle (drawn
// even when the process noise is zero) and one uniform for systematic resampling (drawn even
// when no resampling happens), so the same (seed, stream) gives the same random numbers for
// every assumed noise setting (common random numbers). With zero assumed process noise all
// particles stay identical, and the filter may run a single one (collapse_identical_particles).

#include <cstdint>
#include <vector>

#include "common/observation.hpp"
#include "common/pose2.hpp"
#include "noise/problem.hpp"

namespace lidarcal::noise {

struct FastSlamConfig {
  /// Number of particles. Default 80 (Sharma 2020 ch. 5, all experiments).
  int particles = 80;
  /// Resample (systematic) when the effective sample size falls below this fraction of the
  /// particles; 1 resamples after every stop. Default 0.5.
  double resample_fraction = 0.5;
  /// Leave out of the error samples an observation that initialised its landmark in the
  /// particles (its error is zero by construction, not a sample of the noise). Default false
  /// (the seed counts every reading).
  bool skip_initialising = false;
  /// With zero assumed process noise run a single particle: all N would stay identical, so the
  /// result is the same (up to rounding) at 1/N of the cost. Default true; false runs all N as
  /// the seed does.
  bool collapse_identical_particles = true;

  /// Throws InputError when a value is out of range.
  void validate() const;
};

/// Predicted errors of one sensor, one entry per observation used (Sharma 2020 ch. 3.2).
struct SensorErrorSamples {
  std::vector<double> range_m;          ///< particle-weighted mean range error, metres
  std::vector<double> range_sq_m2;      ///< particle-weighted mean squared range error, m^2
  std::vector<double> bearing_rad;      ///< particle-weighted mean bearing error, radians
  std::vector<double> bearing_sq_rad2;  ///< particle-weighted mean squared bearing error, rad^2
};

struct FastSlamResult {
  std::vector<SensorErrorSamples> errors;  ///< per sensor
  /// particle-weighted mean pose of every stop (after its update)
  std::vector<Pose2> mean_trajectory;
  double log_evidence = 0.0;  ///< sum over updates of log(mean particle likelihood), nats
  int resamplings = 0;        ///< stops after which the particles were resampled
};

/// Runs the filter over the whole problem under the `assumed` noise (every sensor needs
/// positive variances). Throws InputError when `assumed` has fewer sensors than the problem.
FastSlamResult runFastSlam(const NoiseProblem& problem, const NoiseSetting& assumed,
                           const FastSlamConfig& config, std::uint64_t seed, std::uint64_t stream);

}  // namespace lidarcal::noise
