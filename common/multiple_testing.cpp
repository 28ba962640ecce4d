// SPDX-License-Identifier: BSD-3-Clause
#include "common/multiple_testing.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace lidarcal {

std::vector<double> holmAdjust(const std::vector<double>& p) {
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (std::isfinite(p[i])) idx.push_back(i);
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return p[a] < p[b]; });
  std::vector<double> out(p.size(), std::numeric_limits<double>::quiet_NaN());
  const double m = static_cast<double>(idx.size());
  double running = 0.0;
  for (std::size_t r = 0; r < idx.size(); ++r) {
    running = std::max(running, std::min(1.0, (m - static_cast<double>(r)) * p[idx[r]]));
    out[idx[r]] = running;
  }
  return out;
}

}  // namespace lidarcal
