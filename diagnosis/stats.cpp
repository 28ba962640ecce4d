// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/stats.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

namespace lidarcal::diagnosis {

double replicaPValue(double value, const std::vector<double>& replicas, bool two_sided,
                     double* effect_size) {
  std::vector<double> r;
  for (double v : replicas)
    if (std::isfinite(v)) r.push_back(v);
  if (effect_size) *effect_size = 0.0;
  if (!std::isfinite(value) || r.size() < 3) return std::numeric_limits<double>::quiet_NaN();
  const double n = static_cast<double>(r.size());
  const double mean = std::accumulate(r.begin(), r.end(), 0.0) / n;
  double var = 0.0;
  for (double v : r) var += (v - mean) * (v - mean);
  const double sd = std::sqrt(var / (n - 1.0));
  if (!(sd > 0.0)) {
    if (effect_size)
      *effect_size = value == mean
                         ? 0.0
                         : std::copysign(std::numeric_limits<double>::infinity(), value - mean);
    return value == mean || (!two_sided && value < mean) ? 1.0 : 0.0;
  }
  if (effect_size) *effect_size = (value - mean) / sd;
  const double t = (value - mean) / (sd * std::sqrt(1.0 + 1.0 / n));
  const boost::math::students_t dist(n - 1.0);
  const double upper = boost::math::cdf(boost::math::complement(dist, std::abs(t)));
  if (two_sided) return std::min(1.0, 2.0 * upper);
  return t >= 0.0 ? upper : 1.0 - upper;
}

double heldoutPValue(double gain, double se) {
  if (!std::isfinite(gain)) return std::numeric_limits<double>::quiet_NaN();
  if (gain <= 0.0) return 1.0;
  if (!(se > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return 0.5 * std::erfc(gain / se / std::sqrt(2.0));
}

double combinedPValue(double p_heldout, double p_score) {
  return combinedPValue(p_heldout, p_score, std::numeric_limits<double>::quiet_NaN());
}

double combinedPValue(double p_heldout, double p_score, double p_lr) {
  double lowest = std::numeric_limits<double>::infinity();
  int tests = 0;
  for (const double p : {p_heldout, p_score, p_lr})
    if (std::isfinite(p)) {
      lowest = std::min(lowest, p);
      ++tests;
    }
  if (tests == 0) return std::numeric_limits<double>::quiet_NaN();
  return std::min(1.0, tests * lowest);
}

double likelihoodRatioPValue(double statistic, int parameters) {
  if (parameters != 1 || !std::isfinite(statistic)) return std::numeric_limits<double>::quiet_NaN();
  if (statistic <= 0.0) return 1.0;
  return std::erfc(std::sqrt(statistic / 2.0));  // P(chi2_1 > s) = P(|N(0,1)| > sqrt(s))
}

double boundedLikelihoodRatioPValue(double statistic) {
  return statistic > 0.0 ? 0.5 * likelihoodRatioPValue(statistic, 1) : 1.0;
}

double ksDistance(std::vector<double> a, std::vector<double> b) {
  if (a.empty() || b.empty()) return 0.0;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  std::size_t i = 0, j = 0;
  double best = 0.0;
  const double na = static_cast<double>(a.size()), nb = static_cast<double>(b.size());
  while (i < a.size() && j < b.size()) {
    const double x = std::min(a[i], b[j]);
    while (i < a.size() && a[i] <= x) ++i;
    while (j < b.size() && b[j] <= x) ++j;
    best = std::max(best, std::abs(static_cast<double>(i) / na - static_cast<double>(j) / nb));
  }
  return best;
}

double cubeRootChi2(double chi2, double dof) {
  if (!(dof > 0.0)) return 0.0;
  return std::cbrt(std::max(chi2, 0.0) / dof);
}

double huberPsi(double z, double c) { return std::clamp(z, -c, c); }

double meanScore(const std::vector<double>& psi, const std::vector<double>& xs) {
  double u = 0.0, info = 0.0;
  for (std::size_t i = 0; i < psi.size() && i < xs.size(); ++i) {
    u += psi[i] * xs[i];
    info += xs[i] * xs[i];
  }
  return info > 0.0 ? u / std::sqrt(info) : 0.0;
}

double spreadScore(const std::vector<double>& z, const std::vector<double>& g) {
  constexpr double kClip = 3.0;
  const std::size_t n = std::min(z.size(), g.size());
  if (n == 0) return 0.0;
  double mean = 0.0;
  for (std::size_t i = 0; i < n; ++i) mean += g[i] / static_cast<double>(n);
  const double c2 = clippedSquareMean(kClip), v2 = clippedSquareVariance(kClip);
  double u = 0.0, info = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double gi = g[i] - mean;
    u += (std::min(z[i] * z[i], kClip * kClip) - c2) * gi;
    info += v2 * gi * gi;
  }
  return info > 0.0 ? u / std::sqrt(info) : 0.0;
}

double clippedSquareMean(double c) {
  // E[min(Z^2, c^2)] = P(|Z| < c) - 2 c phi(c) + c^2 P(|Z| > c).
  const boost::math::normal n;
  const double tail = 2.0 * boost::math::cdf(boost::math::complement(n, c));
  return (1.0 - tail) - 2.0 * c * boost::math::pdf(n, c) + c * c * tail;
}

double clippedSquareVariance(double c) {
  // E[min(Z^4, c^4)] = 3 P(|Z| < c) - 2 phi(c) (c^3 + 3 c) + c^4 P(|Z| > c).
  const boost::math::normal n;
  const double tail = 2.0 * boost::math::cdf(boost::math::complement(n, c));
  const double m4 = 3.0 * (1.0 - tail) - 2.0 * boost::math::pdf(n, c) * (c * c * c + 3.0 * c) +
                    c * c * c * c * tail;
  const double m2 = clippedSquareMean(c);
  return m4 - m2 * m2;
}

}  // namespace lidarcal::diagnosis
