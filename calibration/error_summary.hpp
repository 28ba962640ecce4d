// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How far measured distances lie from reference ones, summed up over the entries with the
// uncertainty that the number of entries leaves: the RMS error with its standard error, and
// raw against corrected as the MSE ratio (Alhashimi et al. 2021, eq. 31) with an interval.
// Each entry (one target at one stop) counts once; its error is taken as one draw of the
// sensor's error over the distances measured, so the spread between entries is the yardstick.

#include <cstddef>
#include <vector>

namespace lidarcal::calibration {

/// sqrt(mean e^2) over the entries and its standard error by the delta method on the mean
/// square, SE(mean e^2) / (2 RMS), with SE(mean e^2) the sample standard deviation of e^2 over
/// sqrt(n). se_m is NaN with fewer than 2 entries; rms_m NaN with none.
struct RmsError {
  double rms_m = 0.0;
  double se_m = 0.0;
  std::size_t entries = 0;
};
RmsError rmsError(const std::vector<double>& errors_m);

/// raw MSE / corrected MSE over the same entries (paired), with the central interval of
/// probability `level`: exp(ln ratio +- t SE), SE of ln ratio by the delta method with the two
/// mean squares' covariance over the entries, t the Student-t quantile with entries - 1 degrees
/// of freedom. Above 1 the correction helps. ratio NaN without a pair or when the corrected MSE
/// is 0; the interval NaN with fewer than 2 pairs.
struct MseRatio {
  double ratio = 0.0;
  double low = 0.0, high = 0.0;  ///< the interval's ends
  double level = 0.95;
  std::size_t entries = 0;
};
MseRatio mseRatio(const std::vector<double>& raw_errors_m,
                  const std::vector<double>& corrected_errors_m, double level = 0.95);

}  // namespace lidarcal::calibration
