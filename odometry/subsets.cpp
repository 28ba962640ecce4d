// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/subsets.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <boost/math/distributions/chi_squared.hpp>

namespace lidarcal::odometry {
namespace {

/// Mean and spread of the ok subsets' estimates, the mean of their standard errors, and the
/// ratio with its interval.
void summarise(SubsetScatter& out) {
  const double k = out.subsets_ok;
  for (const OdometryResult& r : out.subsets)
    if (r.ok()) {
      out.mean += r.estimate.toVector() / k;
      out.mean_standard_error += r.standardErrors() / k;
    }
  for (const OdometryResult& r : out.subsets)
    if (r.ok()) out.spread += (r.estimate.toVector() - out.mean).cwiseAbs2() / (k - 1.0);
  out.spread = out.spread.cwiseSqrt();
  const boost::math::chi_squared chi2(k - 1.0);
  const double low = std::sqrt((k - 1.0) / boost::math::quantile(chi2, 0.975));
  const double high = std::sqrt((k - 1.0) / boost::math::quantile(chi2, 0.025));
  out.ratio = out.spread.cwiseQuotient(out.mean_standard_error);
  out.ratio_low = out.ratio * low;
  out.ratio_high = out.ratio * high;
}

}  // namespace

SubsetScatter scatterOverSubsets(const std::vector<OdometrySample>& samples, int count,
                                 const OdometrySettings& settings, SubsetSplit split) {
  if (count < 2) throw std::invalid_argument("scatterOverSubsets: count must be at least 2");
  SubsetScatter out;
  const std::size_t n = samples.size(), parts = static_cast<std::size_t>(count);
  for (std::size_t s = 0; s < parts; ++s) {
    // A copy (48 bytes a sample) keeps calibrateOdometry's input a plain list of samples.
    std::vector<OdometrySample> subset;
    if (split == SubsetSplit::consecutive) {
      out.first_sample.push_back(n * s / parts);
      subset.assign(samples.begin() + static_cast<std::ptrdiff_t>(n * s / parts),
                    samples.begin() + static_cast<std::ptrdiff_t>(n * (s + 1) / parts));
    } else {
      out.first_sample.push_back(s);
      for (std::size_t i = s; i < n; i += parts) subset.push_back(samples[i]);
    }
    out.subsets.push_back(calibrateOdometry(subset, settings));
    out.subsets_ok += out.subsets.back().ok() ? 1 : 0;
  }
  if (out.subsets_ok < 2) {
    out.status = {StatusCode::too_few_samples,
                  std::to_string(out.subsets_ok) + " of " + std::to_string(count) +
                      " subsets gave an estimate; a scatter needs two or more (fewer subsets, or "
                      "a longer recording)"};
    return out;
  }
  summarise(out);
  return out;
}

}  // namespace lidarcal::odometry
