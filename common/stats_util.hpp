// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Small numeric helpers shared across the libraries: the non-finite constants, ln(2 pi), the
// medians and a one-dimensional maximiser. One definition each.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace lidarcal {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();  ///< "no value"
inline constexpr double kInf = std::numeric_limits<double>::infinity();
/// ln(2 pi), the Gaussian log-density's constant
inline constexpr double kLog2Pi = 1.8378770664093453;

/// Median: the middle value, or the mean of the two middle values for an even count; NaN when
/// empty.
inline double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

/// Upper median: the value at position n / 2 of the sorted values (the median for an odd count,
/// the upper of the two middle values for an even one; no averaging); NaN when empty.
inline double upperMedian(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// Maximum of a unimodal function on [lo, hi] by ternary search: `iterations` times the third
/// on the lower side of the two inner points is dropped; returns the middle of what is left.
template <class Fn>
double ternaryMax(Fn fn, double lo, double hi, int iterations) {
  for (int i = 0; i < iterations; ++i) {
    const double m1 = lo + (hi - lo) / 3.0, m2 = hi - (hi - lo) / 3.0;
    if (fn(m1) < fn(m2))
      lo = m1;
    else
      hi = m2;
  }
  return 0.5 * (lo + hi);
}

/// Probability that a normal variable (mean mu, standard deviation s) falls in [lo, hi],
/// computed on the side of the tail it lies in (no cancellation far from the mean).
inline double normalMass(double lo, double hi, double mu, double s) {
  const double a = (lo - mu) / (s * std::sqrt(2.0)), b = (hi - mu) / (s * std::sqrt(2.0));
  if (a > 0.0) return 0.5 * (std::erfc(a) - std::erfc(b));
  if (b < 0.0) return 0.5 * (std::erfc(-b) - std::erfc(-a));
  return 1.0 - 0.5 * (std::erfc(b) + std::erfc(-a));
}

/// Resultant length |mean exp(2 pi i y / q)| of readings y on a grid of step q: near 1 when the
/// readings are multiples of q, about 1/sqrt(n) when they are not.
inline double gridResultant(const std::vector<double>& y_m, double q_m) {
  if (y_m.empty() || !(q_m > 0.0)) return 0.0;
  constexpr double kTwoPi = 6.283185307179586;
  double c = 0.0, s = 0.0;
  for (double v : y_m) {
    const double a = kTwoPi * (v / q_m - std::floor(v / q_m));
    c += std::cos(a);
    s += std::sin(a);
  }
  return std::hypot(c, s) / static_cast<double>(y_m.size());
}

/// Coarsest grid the readings lie on, metres (0 when none of 0.1, 0.25, 0.5, 1, 2, 5, 10 and
/// 20 mm fits): the sensor's range resolution when it reports rounded ranges (quantisation).
inline double detectReadingGrid(const std::vector<double>& y_m) {
  double best = 0.0;
  for (double q : {1e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2})
    if (gridResultant(y_m, q) > 0.9) best = q;
  return best;
}

}  // namespace lidarcal
