// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How much closer corrected ranges are to the truth than raw ones.
//   MSE ratio (Alhashimi et al. 2021 eq. 31): MSE(d, raw) / MSE(d, corrected)
//   normalised MSE (Alhashimi et al. 2016 eqs. 31-32): (1/N) sum (x - d)^2 / d^2 for x raw or
//   corrected

#include <vector>

#include "common/pose2.hpp"

namespace lidarcal::calibration {

struct RangeComparison {
  std::size_t n = 0;              ///< readings compared (finite truth, raw and corrected)
  double mse_raw_m2 = 0.0;        ///< MSE of raw readings against the truth
  double mse_corrected_m2 = 0.0;  ///< MSE of corrected readings against the truth
  double mse_ratio = 0.0;         ///< Alhashimi et al. 2021 eq. 31
  double nmse_raw = 0.0;          ///< Alhashimi et al. 2016 eq. 32
  double nmse_corrected = 0.0;    ///< Alhashimi et al. 2016 eq. 31
};

/// Compares; entries with a non-finite value are skipped.
RangeComparison compareRanges(const std::vector<double>& truth_m, const std::vector<double>& raw_m,
                              const std::vector<double>& corrected_m);

/// Scale of the least-squares similarity transform (Umeyama 1991) taking the points `from`
/// onto `to`: how much longer the commanded path is than the true one, the odometry scale
/// error that no self-calibration can see.
double similarityScale(const std::vector<Pose2>& from, const std::vector<Pose2>& to);

}  // namespace lidarcal::calibration
