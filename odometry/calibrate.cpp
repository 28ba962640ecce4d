// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/calibrate.hpp"

#include <numeric>

#include "odometry/closed_form.hpp"
#include "odometry/covariance.hpp"
#include "odometry/trimming.hpp"

namespace lidarcal::odometry {

Vector6 OdometryResult::standardErrors() const { return covariance.diagonal().cwiseSqrt(); }

OdometryResult calibrateOdometry(const std::vector<OdometrySample>& samples,
                                 const OdometrySettings& settings) {
  settings.validate();
  OdometryResult result;
  result.samples_total = samples.size();
  std::vector<std::size_t> kept(samples.size());
  std::iota(kept.begin(), kept.end(), std::size_t{0});

  // 1. The closed form on every sample.
  ClosedFormFit fit = fitClosedForm(samples, kept, settings);
  result.fits = 1;
  // 2. Trim the worst disagreements and refit; the residual variances come from the samples
  //    kept after the first round (all of them without trimming).
  std::vector<std::size_t> variance_set = kept;
  for (int round = 1; round <= settings.trimming_rounds && fit.ok(); ++round) {
    kept = trimRound(samples, kept, fit.params, settings.trim_percentile);
    if (round == 1) variance_set = kept;
    fit = fitClosedForm(samples, kept, settings);
    ++result.fits;
  }
  result.samples_used = kept.size();
  result.samples_trimmed = samples.size() - kept.size();
  if (!fit.ok()) {
    result.status = fit.status;
    return result;
  }
  result.estimate = fit.params;

  // 3. The covariance over the samples one more round would keep.
  const Eigen::Vector3d variances = residualVariances(samples, variance_set, fit.params);
  result.residual_sigma = variances.cwiseSqrt();
  const std::vector<std::size_t> information_set =
      trimRound(samples, kept, fit.params, settings.trim_percentile);
  result.samples_in_covariance = information_set.size();
  const FisherCovariance covariance =
      fisherCovariance(samples, information_set, fit.params, variances);
  result.status = covariance.status;
  result.covariance = covariance.covariance;
  return result;
}

}  // namespace lidarcal::odometry
