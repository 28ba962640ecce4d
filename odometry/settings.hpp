// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The settings of the odometry and laser-mounting calibration (Censi et al. 2013): one struct
// for every stage of odometry/, with the published method's values as defaults.

namespace lidarcal::odometry {

struct OdometrySettings {
  /// Rounds of outlier trimming after the first fit; the estimate is the fit after the last
  /// round (the published result is the fifth fit: 4 rounds). 0: no trimming.
  int trimming_rounds = 4;
  /// Each round drops the samples whose disagreement with the current fit lies above this
  /// percentile, in translation or in rotation (nearest rank: the value at rank
  /// ceil(percentile / 100 * n) of n sorted values is kept), percent in (50, 100]; 100 keeps all.
  double trim_percentile = 99.0;
  /// Fewer samples than this (before or after trimming): too_few_samples. At least 3, the least
  /// the closed form can solve from; the default leaves residual variances worth the name.
  int min_samples = 12;
  /// The rotation fit regresses the laser's turn on the wheels' turns (phi_L T, phi_R T). When
  /// the smaller eigenvalue of their scatter matrix is below this fraction of the larger one,
  /// the wheels turned in one proportion only (only straight driving, only turning in place,
  /// only one curvature) and the two wheel radii cannot be told apart: degenerate_motion.
  double min_wheel_spread = 1e-3;
  /// The same test on the normal matrix of (axle, l_x, l_y), its columns scaled to unit
  /// diagonal: below, the motion does not separate the axle from the laser position (no
  /// translation, or no turning to reveal where the laser sits): degenerate_motion.
  double min_translation_spread = 1e-10;

  void validate() const;  ///< throws InputError naming the setting
};

}  // namespace lidarcal::odometry
