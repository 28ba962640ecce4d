// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/noise_exponent.hpp"
#include "common/stats_util.hpp"

#include <cmath>
#include <numeric>

namespace lidarcal::calibration {

NoiseExponentTest testNoiseExponent(const std::vector<std::vector<double>>& batches,
                                    std::size_t min_batch) {
  NoiseExponentTest t;
  std::vector<const std::vector<double>*> used;
  std::vector<double> fb;  // eq. 13: the batch mean estimates f(d_b)
  for (const auto& b : batches) {
    if (b.size() < std::max<std::size_t>(min_batch, 2)) continue;
    const double mean = std::accumulate(b.begin(), b.end(), 0.0) / static_cast<double>(b.size());
    if (!(mean > 0.0)) continue;
    used.push_back(&b);
    fb.push_back(mean);
    t.readings += b.size();
  }
  t.batches = used.size();
  if (used.size() < 2) return t;
  for (int k = 0; k <= 3; ++k) {
    // Eq. 14 from successive differences, which cancel f(d): var(y_k - y_k-1) = 2 f^2k sigma_e^2.
    // (We divide by the |B_b| - 1 differences a batch has; eq. 14 prints |B_b|.)
    double s = 0.0;
    for (std::size_t b = 0; b < used.size(); ++b) {
      const auto& y = *used[b];
      const double scale = std::pow(fb[b], 2.0 * k);
      double acc = 0.0;
      for (std::size_t i = 1; i < y.size(); ++i) acc += (y[i] - y[i - 1]) * (y[i] - y[i - 1]);
      s += acc / (2.0 * static_cast<double>(y.size() - 1) * scale);
    }
    const double s2 = s / static_cast<double>(used.size());
    t.sigma_e2[static_cast<std::size_t>(k)] = s2;
    // Eq. 15: Gaussian log-likelihood with variance f_b^2k sigma_e^2 around the batch mean.
    double ll = 0.0;
    for (std::size_t b = 0; b < used.size(); ++b) {
      const auto& y = *used[b];
      const double var = std::pow(fb[b], 2.0 * k) * s2;
      for (double v : y) ll -= 0.5 * (kLog2Pi + std::log(var) + (v - fb[b]) * (v - fb[b]) / var);
    }
    t.log_likelihood[static_cast<std::size_t>(k)] = ll;
    if (t.best < 0 || ll > t.log_likelihood[static_cast<std::size_t>(t.best)]) t.best = k;
  }
  return t;
}

}  // namespace lidarcal::calibration
