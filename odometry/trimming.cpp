// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/trimming.hpp"

#include <algorithm>
#include <cmath>

namespace lidarcal::odometry {

double nearestRankPercentile(std::vector<double> values, double percentile) {
  const std::size_t n = values.size();
  const auto rank = static_cast<std::size_t>(std::ceil(percentile / 100.0 * n));
  const std::size_t at = std::min(n, std::max<std::size_t>(rank, 1)) - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(at), values.end());
  return values[at];
}

std::vector<std::size_t> trimRound(const std::vector<OdometrySample>& samples,
                                   const std::vector<std::size_t>& indices,
                                   const OdometryParameters& params, double percentile) {
  if (indices.empty()) return {};
  std::vector<double> translation, rotation;
  translation.reserve(indices.size());
  rotation.reserve(indices.size());
  for (const std::size_t i : indices) {
    const Eigen::Vector3d e = scanMatchResidual(params, samples[i]);
    translation.push_back(e.head<2>().norm());
    rotation.push_back(std::abs(e[2]));
  }
  const double translation_limit = nearestRankPercentile(translation, percentile);
  const double rotation_limit = nearestRankPercentile(rotation, percentile);
  std::vector<std::size_t> kept;
  kept.reserve(indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k)
    if (translation[k] <= translation_limit && rotation[k] <= rotation_limit)
      kept.push_back(indices[k]);
  return kept;
}

}  // namespace lidarcal::odometry
